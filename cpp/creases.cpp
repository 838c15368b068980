#include "creases.hpp"

#include <cmath>
#include <numeric>
#include <unordered_map>
#include <utility>

#include <Eigen/Geometry>

namespace thinburn {
namespace {

int find_root(std::vector<int>& parent, int a) {
  while (parent[a] != a) a = parent[a] = parent[parent[a]];
  return a;
}

struct CreaseEdge {
  int a, b, f, g;  // vertices, faces
};

// A sliver side: every vertex of its faces lies on a crease (a fold made across a row of
// triangles is a strip between two creases a fraction of a millimetre apart). It joins one of
// its neighbours, so the fold is one crease line, and a side's couples turn about it: two
// lines that close would each claim the hinge, and the strip's edges across them would stretch
// by half the turn's change (32 % on a folded letter's strip at 40 s).
std::vector<int> join_slivers(std::size_t vertices, const std::vector<std::array<int, 3>>& f,
                              const std::vector<CreaseEdge>& creases, std::vector<int>& parent) {
  const int nf = static_cast<int>(f.size());
  std::unordered_map<int, bool> all_on_crease;  // root -> every vertex of its faces on a crease
  std::vector<std::uint8_t> on(vertices, 0);
  for (const CreaseEdge& e : creases) on[e.a] = on[e.b] = 1;
  std::vector<int> root(nf);  // each face's side before the joins
  for (int i = 0; i < nf; ++i) {
    root[i] = find_root(parent, i);
    auto [it, fresh] = all_on_crease.try_emplace(root[i], true);
    for (int v : f[i]) it->second = it->second && on[v];
  }
  std::unordered_map<int, bool> joined;
  for (const CreaseEdge& e : creases) {
    const int rf = find_root(parent, e.f), rg = find_root(parent, e.g);
    if (rf == rg) continue;
    const auto sliver = [&](int r) { auto it = all_on_crease.find(r); return it != all_on_crease.end() && it->second && !joined[r]; };
    const int s = sliver(rf) ? rf : sliver(rg) ? rg : -1;
    if (s < 0) continue;
    joined[s] = true;
    parent[s] = s == rf ? rg : rf;
  }
  // The joined slivers' faces, by their sides before the joins: the finds above compress the
  // paths past a joined sliver's root (walking up from a face found 2 of a 178-face strip).
  std::vector<int> out;
  for (int i = 0; i < nf; ++i)
    if (joined[root[i]]) out.push_back(i);
  return out;
}

}  // namespace

Creases find_creases(const std::vector<Eigen::Vector3d>& v, const std::vector<std::array<int, 3>>& f,
                     double angle) {
  const int nf = static_cast<int>(f.size());
  Creases out;
  out.vertex.assign(v.size(), 0);
  std::vector<Eigen::Vector3d> normal(nf);
  for (int i = 0; i < nf; ++i)
    normal[i] = (v[f[i][1]] - v[f[i][0]]).cross(v[f[i][2]] - v[f[i][0]]).normalized();
  // Union-find over faces joined by their non-crease edges.
  std::vector<int> parent(nf);
  std::iota(parent.begin(), parent.end(), 0);
  std::unordered_map<std::uint64_t, int> first_face;
  first_face.reserve(f.size() * 2);
  std::unordered_map<std::uint64_t, int> faces_of_edge;
  std::vector<CreaseEdge> creases;
  const double cos_limit = std::cos(angle);
  for (int i = 0; i < nf; ++i)
    for (int k = 0; k < 3; ++k) {
      int a = f[i][k], b = f[i][(k + 1) % 3];
      if (a > b) std::swap(a, b);
      const std::uint64_t key = (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
      ++faces_of_edge[key];
      const auto [it, fresh] = first_face.try_emplace(key, i);
      if (fresh) continue;
      const int g = it->second;
      if (normal[i].dot(normal[g]) < cos_limit)
        creases.push_back({a, b, i, g});
      else
        parent[find_root(parent, i)] = find_root(parent, g);
    }
  if (creases.empty()) return out;
  // A point on a sliver takes the side beyond it, not the sliver's: the sliver's far line lies
  // off its new side's surface, where the embedding would carry it at an offset along the turning
  // normal (its edges 10 % at 40 s), while the fits of the two sides meet within 0.1 mm.
  out.sliver.assign(v.size(), 0);
  for (int i : join_slivers(v.size(), f, creases, parent))
    for (int k : f[i]) out.sliver[k] = 1;
  std::vector<int> crease_degree(v.size(), 0);
  for (const CreaseEdge& e : creases) {
    if (find_root(parent, e.f) == find_root(parent, e.g)) continue;  // inside a joined sliver
    out.vertex[e.a] = out.vertex[e.b] = 1;
    ++crease_degree[e.a], ++crease_degree[e.b];
    ++out.edges;
  }
  if (out.edges == 0) {  // every crease was a sliver's: none left
    out.sliver.clear();
    return out;
  }
  std::vector<std::uint8_t> boundary(v.size(), 0);
  for (const auto& [key, count] : faces_of_edge)
    if (count == 1) boundary[key >> 32] = boundary[key & 0xffffffffu] = 1;
  for (std::size_t i = 0; i < v.size(); ++i)
    if (out.vertex[i] && (boundary[i] || crease_degree[i] != 2)) out.ends.push_back(static_cast<int>(i));
  out.face_side.assign(nf, -1);
  std::vector<int> side_of_root(nf, -1);
  for (int i = 0; i < nf; ++i) {
    int& s = side_of_root[find_root(parent, i)];
    if (s < 0) s = out.sides++;
    out.face_side[i] = s;
  }
  return out;
}

}  // namespace thinburn
