#include "surface_cells.hpp"

#include "creases.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <utility>

#include <Eigen/Geometry>

namespace thinburn {
namespace {

using Vec3 = Eigen::Vector3d;
using Face = std::array<int, 3>;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
// A cell lies on the sides of the faces within this many spacings of it (cell_sides).
constexpr double kCreaseReach = 0.25;

struct Mesh {
  std::vector<Vec3> v;
  std::vector<Face> f;
};

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
}

double face_area(const Mesh& m, const Face& f) {
  return 0.5 * (m.v[f[1]] - m.v[f[0]]).cross(m.v[f[2]] - m.v[f[0]]).norm();
}

void check_input(const SurfVerts& V, const SurfFaces& F) {
  if (V.rows() < 3) throw std::invalid_argument("vertices: need at least 3 vertices");
  if (F.rows() < 1) throw std::invalid_argument("faces: need at least one face");
  if (!V.allFinite()) throw std::invalid_argument("vertices must be finite (no NaN or inf)");
  for (Eigen::Index i = 0; i < F.rows(); ++i) {
    for (int k = 0; k < 3; ++k)
      if (F(i, k) < 0 || F(i, k) >= V.rows())
        throw std::invalid_argument("faces: index " + std::to_string(F(i, k)) + " in face " +
                                    std::to_string(i) + " is out of range [0, " +
                                    std::to_string(V.rows()) + ")");
    if (F(i, 0) == F(i, 1) || F(i, 1) == F(i, 2) || F(i, 0) == F(i, 2))
      throw std::invalid_argument("faces: face " + std::to_string(i) + " repeats a vertex");
  }
}

// Union of vertices within tol of each other (a hash grid of cell size tol, 27 buckets per
// query), so that duplicated seam vertices become one: the front must not see UV seams.
std::vector<int> weld(const SurfVerts& V, double tol) {
  const int n = static_cast<int>(V.rows());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  if (tol > 0.0) {
    struct KeyHash {
      std::size_t operator()(const std::array<long long, 3>& k) const {
        return static_cast<std::size_t>(k[0] * 73856093LL ^ k[1] * 19349663LL ^ k[2] * 83492791LL);
      }
    };
    std::unordered_map<std::array<long long, 3>, std::vector<int>, KeyHash> grid;
    auto key = [&](int i, int dx, int dy, int dz) {
      return std::array<long long, 3>{static_cast<long long>(std::floor(V(i, 0) / tol)) + dx,
                                      static_cast<long long>(std::floor(V(i, 1) / tol)) + dy,
                                      static_cast<long long>(std::floor(V(i, 2) / tol)) + dz};
    };
    for (int i = 0; i < n; ++i) {
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            auto it = grid.find(key(i, dx, dy, dz));
            if (it == grid.end()) continue;
            for (int j : it->second)
              if ((V.row(i) - V.row(j)).norm() <= tol) parent[root(i)] = root(j);
          }
      grid[key(i, 0, 0, 0)].push_back(i);
    }
  }
  std::vector<int> out(n);
  for (int i = 0; i < n; ++i) out[i] = root(i);
  return out;
}

// The welded mesh: faces on representative vertices, degenerate faces dropped, unreferenced
// vertices removed. input_to_mesh maps input vertices to mesh vertices (-1: on no face).
Mesh welded_mesh(const SurfVerts& V, const SurfFaces& F, double tol, std::vector<int>* input_to_mesh,
                 std::vector<int>* face_origin) {
  const std::vector<int> rep = weld(V, tol);
  const int n = static_cast<int>(V.rows());
  std::vector<int> compact(n, -1);
  Mesh m;
  auto vid = [&](int i) {
    const int r = rep[i];
    if (compact[r] < 0) {
      compact[r] = static_cast<int>(m.v.size());
      m.v.push_back(V.row(r).transpose());
    }
    return compact[r];
  };
  const double bbox = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  const double min_area = 1e-14 * bbox * bbox;
  for (Eigen::Index i = 0; i < F.rows(); ++i) {
    const int a = rep[F(i, 0)], b = rep[F(i, 1)], c = rep[F(i, 2)];
    if (a == b || b == c || a == c) continue;
    const Vec3 pa = V.row(a), pb = V.row(b), pc = V.row(c);
    if (!(0.5 * (pb - pa).cross(pc - pa).norm() > min_area)) continue;
    m.f.push_back({vid(F(i, 0)), vid(F(i, 1)), vid(F(i, 2))});
    face_origin->push_back(static_cast<int>(i));
  }
  input_to_mesh->assign(n, -1);
  for (int i = 0; i < n; ++i) (*input_to_mesh)[i] = compact[rep[i]];
  return m;
}

// Edge -> incident faces. Throws on an edge with more than two faces (non-manifold).
std::unordered_map<std::uint64_t, std::array<int, 2>> edge_faces(const Mesh& m,
                                                                 const std::vector<int>& origin) {
  std::unordered_map<std::uint64_t, std::array<int, 2>> ef;
  ef.reserve(m.f.size() * 2);
  for (int i = 0; i < static_cast<int>(m.f.size()); ++i)
    for (int k = 0; k < 3; ++k) {
      auto [it, fresh] = ef.try_emplace(edge_key(m.f[i][k], m.f[i][(k + 1) % 3]), std::array<int, 2>{i, -1});
      if (fresh) continue;
      if (it->second[1] >= 0)
        throw std::invalid_argument("faces: an edge is shared by more than two faces (faces " +
                                    std::to_string(origin[it->second[0]]) + ", " +
                                    std::to_string(origin[it->second[1]]) + ", " +
                                    std::to_string(origin[i]) + "): the mesh is not manifold");
      it->second[1] = i;
    }
  return ef;
}

bool has_directed(const Face& f, int a, int b) {
  for (int k = 0; k < 3; ++k)
    if (f[k] == a && f[(k + 1) % 3] == b) return true;
  return false;
}

// Consistent orientation per connected piece (breadth-first over shared edges), so that the
// cells' area-weighted normals do not cancel. A non-orientable piece keeps one flip seam.
void orient(Mesh& m, const std::unordered_map<std::uint64_t, std::array<int, 2>>& ef) {
  const int nf = static_cast<int>(m.f.size());
  std::vector<std::uint8_t> seen(nf, 0);
  std::vector<int> queue;
  for (int s = 0; s < nf; ++s) {
    if (seen[s]) continue;
    seen[s] = 1;
    queue.assign(1, s);
    for (std::size_t qi = 0; qi < queue.size(); ++qi) {
      const Face f = m.f[queue[qi]];
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        const auto& pair = ef.at(edge_key(a, b));
        const int g = pair[0] == queue[qi] ? pair[1] : pair[0];
        if (g < 0 || seen[g]) continue;
        seen[g] = 1;
        if (has_directed(m.f[g], a, b)) std::swap(m.f[g][0], m.f[g][1]);  // same direction: flip
        queue.push_back(g);
      }
    }
  }
}

// Red-green refinement until no edge is longer than hd: every long edge is split at its
// midpoint (shared by both faces, so the mesh stays conforming); a face with one, two or
// three split edges becomes two, three or four faces. Orientation is kept.
void refine(Mesh& m, double hd) {
  for (int pass = 0; pass < 64; ++pass) {
    std::unordered_map<std::uint64_t, int> mid;
    for (const Face& f : m.f)
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        if ((m.v[a] - m.v[b]).norm() <= hd * (1.0 + 1e-9)) continue;  // margin: pose-proof
        auto [it, fresh] = mid.try_emplace(edge_key(a, b), -1);
        if (fresh) {
          it->second = static_cast<int>(m.v.size());
          m.v.push_back(0.5 * (m.v[a] + m.v[b]));
        }
      }
    if (mid.empty()) return;
    std::vector<Face> out;
    out.reserve(m.f.size() * 3);
    for (const Face& f : m.f) {
      int e[3];  // e[k]: midpoint of the edge opposite f[k], or -1
      int n_split = 0;
      for (int k = 0; k < 3; ++k) {
        auto it = mid.find(edge_key(f[(k + 1) % 3], f[(k + 2) % 3]));
        e[k] = it == mid.end() ? -1 : it->second;
        n_split += e[k] >= 0;
      }
      if (n_split == 0) {
        out.push_back(f);
        continue;
      }
      if (n_split == 3) {
        out.push_back({f[0], e[2], e[1]});
        out.push_back({f[1], e[0], e[2]});
        out.push_back({f[2], e[1], e[0]});
        out.push_back({e[0], e[1], e[2]});
        continue;
      }
      if (n_split == 1) {
        const int k = e[0] >= 0 ? 0 : e[1] >= 0 ? 1 : 2;
        const int v0 = f[k], v1 = f[(k + 1) % 3], v2 = f[(k + 2) % 3], mk = e[k];
        out.push_back({v0, v1, mk});
        out.push_back({v0, mk, v2});
        continue;
      }
      // Two split edges: rotate so the unsplit edge is opposite v0.
      const int k = e[0] < 0 ? 0 : e[1] < 0 ? 1 : 2;
      const int v0 = f[k], v1 = f[(k + 1) % 3], v2 = f[(k + 2) % 3];
      const int m1 = e[(k + 1) % 3], m2 = e[(k + 2) % 3];  // on v2-v0 and v0-v1
      out.push_back({v0, m2, m1});
      // The shorter diagonal; near-ties (regular meshes) by a rule that rotation cannot flip.
      const double l2 = (m.v[m2] - m.v[v2]).norm(), l1 = (m.v[m1] - m.v[v1]).norm();
      if (l2 < l1 * (1.0 - 1e-9) || (l2 <= l1 * (1.0 + 1e-9) && v2 < v1)) {
        out.push_back({m2, v1, v2});
        out.push_back({m2, v2, m1});
      } else {
        out.push_back({m2, v1, m1});
        out.push_back({m1, v1, v2});
      }
    }
    m.f.swap(out);
  }
}

// The dense mesh as a weighted graph (edge lengths) with lumped vertex areas.
struct Graph {
  std::vector<int> off, nbr;
  std::vector<double> len, area;
};

// Edge lengths are rounded to multiples of `quantum` (1e-9 of the dense spacing): regular
// meshes have many exactly tied graph distances, and the sampling must break those ties the
// same way however the mesh is moved (rounding noise of a rotation would break them anew).
Graph graph_of(const Mesh& m, double quantum) {
  const int n = static_cast<int>(m.v.size());
  std::vector<std::uint64_t> keys;
  keys.reserve(m.f.size() * 3);
  Graph g;
  g.area.assign(n, 0.0);
  for (const Face& f : m.f) {
    const double a3 = face_area(m, f) / 3.0;
    for (int k = 0; k < 3; ++k) {
      keys.push_back(edge_key(f[k], f[(k + 1) % 3]));
      g.area[f[k]] += a3;
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  g.off.assign(n + 1, 0);
  for (std::uint64_t k : keys) {
    ++g.off[(k >> 32) + 1];
    ++g.off[(k & 0xffffffffu) + 1];
  }
  for (int i = 0; i < n; ++i) g.off[i + 1] += g.off[i];
  g.nbr.resize(g.off[n]);
  g.len.resize(g.off[n]);
  std::vector<int> fill(g.off.begin(), g.off.end() - 1);
  for (std::uint64_t k : keys) {
    const int a = static_cast<int>(k >> 32), b = static_cast<int>(k & 0xffffffffu);
    const double l = std::max(1.0, std::round((m.v[a] - m.v[b]).norm() / quantum)) * quantum;
    g.nbr[fill[a]] = b, g.len[fill[a]++] = l;
    g.nbr[fill[b]] = a, g.len[fill[b]++] = l;
  }
  return g;
}

struct MinEntry {
  double d;
  int v;
  bool operator>(const MinEntry& o) const { return d > o.d || (d == o.d && v > o.v); }
};
using MinHeap = std::priority_queue<MinEntry, std::vector<MinEntry>, std::greater<MinEntry>>;

// Dijkstra from the entries already in `heap`; improves dist/label. `on_improve` sees every
// vertex whose distance drops (farthest-point sampling keeps its max-heap with it).
template <class F>
void dijkstra(const Graph& g, MinHeap& heap, std::vector<double>& dist, std::vector<int>& label,
              F&& on_improve) {
  while (!heap.empty()) {
    const MinEntry e = heap.top();
    heap.pop();
    if (e.d != dist[e.v]) continue;
    for (int j = g.off[e.v]; j < g.off[e.v + 1]; ++j) {
      const int u = g.nbr[j];
      const double nd = e.d + g.len[j];
      if (!(nd < dist[u])) continue;
      dist[u] = nd;
      label[u] = label[e.v];
      heap.push({nd, u});
      on_improve(u, nd);
    }
  }
}

// Farthest-point sampling: each new seed is the vertex farthest (in graph distance) from all
// seeds so far; unreached pieces are seeded first so that every piece gets a cell. With `rim`
// (per vertex, 1 on the boundary) the boundary is seeded first, until no boundary vertex lies
// farther than rim_gap from a seed; *rim_count says how many seeds that took (they come first).
std::vector<int> farthest_points(const Graph& g, int k, std::vector<int>* label,
                                 const std::vector<std::uint8_t>* rim = nullptr, double rim_gap = 0.0,
                                 int* rim_count = nullptr, const std::vector<int>& ends = {}, int* end_count = nullptr) {
  const int n = static_cast<int>(g.area.size());
  std::vector<double> dist(n, kInf);
  label->assign(n, -1);
  std::priority_queue<std::pair<double, int>> far, far_rim;  // max-heaps, lazy
  std::vector<int> seeds;
  auto seed = [&](int s) {
    (*label)[s] = static_cast<int>(seeds.size());
    seeds.push_back(s);
    dist[s] = 0.0;
    MinHeap heap;
    heap.push({0.0, s});
    dijkstra(g, heap, dist, *label, [&](int u, double d) {
      far.push({d, u});
      if (rim && (*rim)[u]) far_rim.push({d, u});
    });
  };
  // Ends first (a crease's ends, where one-sided fits would otherwise extrapolate), each
  // unless a seed lies within half the rim's gap (a crease as a strip of faces has two ends).
  for (int v : ends)
    if (static_cast<int>(seeds.size()) < k && !(dist[v] <= 0.5 * rim_gap)) seed(v);
  if (end_count) *end_count = static_cast<int>(seeds.size());
  for (int scan_rim = 0; rim && static_cast<int>(seeds.size()) < k;) {
    while (scan_rim < n && !((*rim)[scan_rim] && (*label)[scan_rim] < 0)) ++scan_rim;
    int s = -1;
    if (scan_rim < n) {
      s = scan_rim;
    } else {
      while (!far_rim.empty() && far_rim.top().first != dist[far_rim.top().second]) far_rim.pop();
      if (far_rim.empty() || far_rim.top().first <= rim_gap) break;
      s = far_rim.top().second;
      far_rim.pop();
    }
    seed(s);
  }
  if (rim_count) *rim_count = static_cast<int>(seeds.size());
  int scan = 0;
  while (true) {
    while (scan < n && (*label)[scan] >= 0) ++scan;
    int s = -1;
    if (scan < n) {
      s = scan;
    } else {
      if (static_cast<int>(seeds.size()) >= k) break;
      while (!far.empty() && (far.top().first != dist[far.top().second] || dist[far.top().second] == 0.0)) far.pop();
      if (far.empty()) break;
      s = far.top().second;
      far.pop();
    }
    seed(s);
  }
  return seeds;
}

void voronoi(const Graph& g, const std::vector<int>& seeds, std::vector<int>* label) {
  const int n = static_cast<int>(g.area.size());
  std::vector<double> dist(n, kInf);
  label->assign(n, -1);
  MinHeap heap;
  for (int i = 0; i < static_cast<int>(seeds.size()); ++i) {
    dist[seeds[i]] = 0.0;
    (*label)[seeds[i]] = i;
    heap.push({0.0, seeds[i]});
  }
  dijkstra(g, heap, dist, *label, [](int, double) {});
}

// One Lloyd step: each seed moves to the vertex of its region nearest the region's centroid;
// the first `rim_seeds` seeds to the nearest of its region's rim vertices (if it has any), but
// the first `fixed` stay.
void lloyd_step(const Mesh& m, const Graph& g, const std::vector<int>& label, double quantum,
                std::vector<int>* seeds, const std::vector<std::uint8_t>* rim = nullptr, int rim_seeds = 0,
                int fixed = 0) {
  const int k = static_cast<int>(seeds->size());
  std::vector<Vec3> c(k, Vec3::Zero());
  std::vector<double> w(k, 0.0), best(k, kInf);
  for (int v = 0; v < static_cast<int>(label.size()); ++v) {
    c[label[v]] += g.area[v] * m.v[v];
    w[label[v]] += g.area[v];
  }
  for (int i = 0; i < k; ++i) c[i] /= w[i];
  for (int v = 0; v < static_cast<int>(label.size()); ++v) {
    const int i = label[v];
    if (i < fixed || (i < rim_seeds && !(*rim)[v])) continue;
    const double d = std::round((m.v[v] - c[i]).norm() / quantum);  // ties as in graph_of
    if (d < best[i]) best[i] = d, (*seeds)[i] = v;
  }
}

// Angle deficit 2 pi - (sum of the corner angles) at each vertex; 0 on the boundary, where
// the deficit measures the boundary's turning rather than the surface's curvature: that turning,
// pi - (sum of the corner angles), goes to *rim_turn (0 off the boundary).
std::vector<double> angle_deficits(const Mesh& m, std::vector<std::uint8_t>* on_boundary,
                                   std::vector<double>* rim_turn) {
  const int n = static_cast<int>(m.v.size());
  std::vector<double> angle(n, 0.0);
  std::unordered_map<std::uint64_t, int> edge_count;
  edge_count.reserve(m.f.size() * 2);
  for (const Face& f : m.f)
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3], c = f[(k + 2) % 3];
      const Vec3 u = m.v[b] - m.v[a], w = m.v[c] - m.v[a];
      angle[a] += std::atan2(u.cross(w).norm(), u.dot(w));
      ++edge_count[edge_key(a, b)];
    }
  std::vector<std::uint8_t> boundary(n, 0);
  for (const auto& [key, count] : edge_count)
    if (count == 1) boundary[key >> 32] = boundary[key & 0xffffffffu] = 1;
  std::vector<double> out(n, 0.0);
  rim_turn->assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    out[i] = boundary[i] ? 0.0 : 2.0 * kPi - angle[i];
    if (boundary[i]) (*rim_turn)[i] = kPi - angle[i];
  }
  *on_boundary = std::move(boundary);
  return out;
}

void csr(int n, const std::vector<std::pair<int, int>>& pairs, std::vector<int>* off, std::vector<int>* idx) {
  off->assign(n + 1, 0);
  for (const auto& p : pairs) ++(*off)[p.first + 1];
  for (int i = 0; i < n; ++i) (*off)[i + 1] += (*off)[i];
  idx->resize(pairs.size());
  std::vector<int> fill(off->begin(), off->end() - 1);
  for (const auto& p : pairs) (*idx)[fill[p.first]++] = p.second;
}

// Barycentric weights of p (projected into the triangle's plane) in (a, b, c), clamped onto
// the triangle; returns the distance from p to the clamped point (inf if degenerate).
double barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, std::array<double, 3>* w) {
  const Vec3 e1 = b - a, e2 = c - a, d = p - a;
  const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2);
  const double det = d11 * d22 - d12 * d12;
  if (!(det > 0.0)) return kInf;
  double u = (d22 * e1.dot(d) - d12 * e2.dot(d)) / det;
  double v = (d11 * e2.dot(d) - d12 * e1.dot(d)) / det;
  if (u < 0.0 || v < 0.0 || u + v > 1.0) {  // outside: the nearest point of the three edges
    double best = kInf;
    const Vec3* P[3] = {&a, &b, &c};
    for (int k = 0; k < 3; ++k) {
      const Vec3 &s = *P[k], &t = *P[(k + 1) % 3];
      const double l = std::clamp((p - s).dot(t - s) / (t - s).squaredNorm(), 0.0, 1.0);
      const double dist = (p - (s + l * (t - s))).squaredNorm();
      if (dist >= best) continue;
      best = dist;
      std::array<double, 3> wk{0.0, 0.0, 0.0};
      wk[k] = 1.0 - l, wk[(k + 1) % 3] = l;
      u = wk[1], v = wk[2];
    }
  }
  *w = {1.0 - u - v, u, v};
  const Vec3 q = a + u * e1 + v * e2;
  return (p - q).norm();
}

// The sides each cell lies on: those of the faces around the dense vertices within `radius`
// (graph distance) of its seed. A cell seeded on a crease lies on both its sides, and so does
// one within a hair of it (a fold across a row of triangles leaves its seeds 0.86 mm from the
// line that stays a crease once the strip joined a side). *vertex_side gets the side of each
// vertex (one of them for a vertex on a crease).
std::vector<std::pair<int, int>> cell_sides(const Graph& g, const std::vector<Face>& faces, const Creases& creases,
                                            const std::vector<int>& seeds, double radius,
                                            std::vector<int>* vertex_side) {
  const int n = static_cast<int>(g.area.size());
  std::vector<std::pair<int, int>> vs;  // (vertex, side of a face around it)
  for (std::size_t i = 0; i < faces.size(); ++i)
    for (int v : faces[i]) vs.push_back({v, creases.face_side[i]});
  std::sort(vs.begin(), vs.end());
  vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
  std::vector<int> off, idx;
  csr(n, vs, &off, &idx);
  vertex_side->assign(n, -1);
  for (int v = 0; v < n; ++v)
    if (off[v] < off[v + 1]) (*vertex_side)[v] = idx[off[v]];
  std::vector<std::pair<int, int>> out;
  std::vector<double> dist(n, kInf);
  std::vector<int> touched;
  for (int c = 0; c < static_cast<int>(seeds.size()); ++c) {
    MinHeap heap;
    dist[seeds[c]] = 0.0;
    touched.assign(1, seeds[c]);
    heap.push({0.0, seeds[c]});
    while (!heap.empty()) {
      const MinEntry e = heap.top();
      heap.pop();
      if (e.d != dist[e.v]) continue;
      for (int q = off[e.v]; q < off[e.v + 1]; ++q) out.push_back({c, idx[q]});
      for (int j = g.off[e.v]; j < g.off[e.v + 1]; ++j) {
        const int u = g.nbr[j];
        const double nd = e.d + g.len[j];
        if (nd > radius || !(nd < dist[u])) continue;
        if (dist[u] == kInf) touched.push_back(u);
        dist[u] = nd;
        heap.push({nd, u});
      }
    }
    for (int v : touched) dist[v] = kInf;
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace

KdTree3::KdTree3(const std::vector<Eigen::Vector3d>& points) : pts_(points) {
  idx_.resize(pts_.size());
  std::iota(idx_.begin(), idx_.end(), 0);
  axis_.assign(pts_.size(), 0);
  build(0, static_cast<int>(pts_.size()));
}

// Median split on the widest axis of the range; the median sits at (lo + hi) / 2.
void KdTree3::build(int lo, int hi) {
  if (hi - lo <= 1) return;
  Vec3 mn = pts_[idx_[lo]], mx = mn;
  for (int i = lo + 1; i < hi; ++i) {
    mn = mn.cwiseMin(pts_[idx_[i]]);
    mx = mx.cwiseMax(pts_[idx_[i]]);
  }
  int axis;
  (mx - mn).maxCoeff(&axis);
  const int mid = (lo + hi) / 2;
  std::nth_element(idx_.begin() + lo, idx_.begin() + mid, idx_.begin() + hi,
                   [&](int a, int b) { return pts_[a][axis] < pts_[b][axis]; });
  axis_[mid] = static_cast<signed char>(axis);
  build(lo, mid);
  build(mid + 1, hi);
}

void KdTree3::search(int lo, int hi, const Vec3& q, int* best, double* best_d2) const {
  if (lo >= hi) return;
  const int mid = (lo + hi) / 2;
  const Vec3& p = pts_[idx_[mid]];
  const double d2 = (p - q).squaredNorm();
  if (d2 < *best_d2 || (d2 == *best_d2 && idx_[mid] < *best)) *best_d2 = d2, *best = idx_[mid];
  if (hi - lo == 1) return;
  const double diff = q[axis_[mid]] - p[axis_[mid]];
  if (diff < 0.0) {
    search(lo, mid, q, best, best_d2);
    if (diff * diff <= *best_d2) search(mid + 1, hi, q, best, best_d2);
  } else {
    search(mid + 1, hi, q, best, best_d2);
    if (diff * diff <= *best_d2) search(lo, mid, q, best, best_d2);
  }
}

int KdTree3::nearest(const Vec3& q) const {
  int best = -1;
  double d2 = kInf;
  search(0, static_cast<int>(pts_.size()), q, &best, &d2);
  return best;
}

SurfaceCells::SurfaceCells(const SurfVerts& V, const SurfFaces& F, const CellOptions& opt) {
  if (opt.spacing <= 0.0 && opt.cells < 1) throw std::invalid_argument("cells must be >= 1");
  if (!(std::isfinite(opt.spacing) && opt.spacing >= 0.0))
    throw std::invalid_argument("spacing must be finite and >= 0");
  if (!(std::isfinite(opt.weld_tol) && opt.weld_tol >= 0.0))
    throw std::invalid_argument("weld_tol must be finite and >= 0");
  if (!(std::isfinite(opt.refine) && opt.refine >= 1.0)) throw std::invalid_argument("refine must be >= 1");
  if (opt.lloyd_iters < 0) throw std::invalid_argument("lloyd_iters must be >= 0");
  check_input(V, F);
  const double diag = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  // The faces in a canonical order (each rotated to start at its smallest vertex, orientation
  // kept, then sorted): the cells depend on the set of triangles, not on the order a tool hands
  // them over (Blender's triangulation order changes between runs). origin maps back to the
  // caller's face indices for error messages.
  std::vector<int> order(F.rows());
  SurfFaces G(F.rows(), 3);
  for (Eigen::Index i = 0; i < F.rows(); ++i) {
    int k = 0;
    if (F(i, 1) < F(i, k)) k = 1;
    if (F(i, 2) < F(i, k)) k = 2;
    G.row(i) << F(i, k), F(i, (k + 1) % 3), F(i, (k + 2) % 3);
  }
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    for (int k = 0; k < 3; ++k)
      if (G(a, k) != G(b, k)) return G(a, k) < G(b, k);
    return a < b;
  });
  SurfFaces sorted(F.rows(), 3);
  for (Eigen::Index i = 0; i < F.rows(); ++i) sorted.row(i) = G.row(order[i]);
  std::vector<int> input_to_mesh, origin;
  Mesh m = welded_mesh(V, sorted, opt.weld_tol * diag, &input_to_mesh, &origin);
  for (int& o : origin) o = order[o];
  for (const Face& f : m.f) area_total_ += face_area(m, f);
  if (m.f.empty() || !(area_total_ > 0.0)) throw std::invalid_argument("vertices: the mesh has zero area");
  orient(m, edge_faces(m, origin));

  // A hexagonal packing at spacing h has (sqrt(3)/2) h^2 of area per cell: `cells`^2 cells.
  const double per_cell = opt.spacing > 0.0 ? 0.5 * std::sqrt(3.0) * opt.spacing * opt.spacing
                                            : area_total_ / (static_cast<double>(opt.cells) * opt.cells);
  h_ = std::sqrt(per_cell / (0.5 * std::sqrt(3.0)));
  const double want = area_total_ / per_cell;
  if (want > 5e7) throw std::invalid_argument("cells/spacing: more than 5e7 cells requested");
  const int k = std::max(1, static_cast<int>(std::lround(want)));
  const int n_input_mesh = static_cast<int>(m.v.size());
  refine(m, h_ / opt.refine);
  n_dense_ = static_cast<int>(m.v.size());
  const Graph g = graph_of(m, 1e-9 * h_ / opt.refine);

  std::vector<int> label;
  std::vector<std::uint8_t> dense_boundary;
  std::vector<double> rim_turn;
  const std::vector<double> deficit = angle_deficits(m, &dense_boundary, &rim_turn);
  // Rim seeds until no rim vertex lies farther than 0.6 spacings from one: farthest points on a
  // line halve their gaps, and at 0.5 a straight edge's gaps of exactly one spacing were
  // halved again (64 of a 20 cm sheet's 74 couples on its rim).
  // Creases are seeded as the rim is: a point near a crease is embedded from its own side's
  // couples (docs/lattice.md, "Creases"), which must reach the crease, not stop short of it.
  const Creases creases = opt.crease_angle > 0.0 ? find_creases(m.v, m.f, opt.crease_angle) : Creases{};
  std::vector<std::uint8_t> seed_first;
  if (creases.edges > 0) {
    seed_first.assign(n_dense_, 0);
    for (int v = 0; v < n_dense_; ++v) seed_first[v] = (opt.rim_seeds && dense_boundary[v]) || creases.vertex[v];
  }
  const std::vector<std::uint8_t>* rim =
      creases.edges > 0 ? &seed_first : opt.rim_seeds ? &dense_boundary : nullptr;
  // The rim's corners (where it turns by more than a crease does) are seeded first, with the
  // creases' ends: a corner between rim couples was extrapolated from couples a spacing inside
  // it (an A4 letter's corner 1.2 cm beyond its control triangles at 64 cells), where
  // self-contact, which keeps couples from the control triangles, could not hold it.
  std::vector<int> ends = creases.ends;
  if (opt.rim_seeds && opt.crease_angle > 0.0)
    for (int v = 0; v < n_dense_; ++v)
      if (rim_turn[v] > opt.crease_angle && std::find(ends.begin(), ends.end(), v) == ends.end()) ends.push_back(v);
  int rim_seeds = 0;
  int end_seeds = 0;
  std::vector<int> seeds = farthest_points(g, k, &label, rim, 0.6 * h_, &rim_seeds, ends, &end_seeds);
  for (int it = 0; it < opt.lloyd_iters; ++it) {
    lloyd_step(m, g, label, 1e-9 * h_ / opt.refine, &seeds, rim, rim_seeds, end_seeds);
    voronoi(g, seeds, &label);
  }
  const int nc = static_cast<int>(seeds.size());

  pos_.resize(nc);
  for (int i = 0; i < nc; ++i) pos_[i] = m.v[seeds[i]];
  area_.assign(nc, 0.0);
  for (int v = 0; v < n_dense_; ++v) area_[label[v]] += g.area[v];
  gauss_.assign(nc, 0.0);
  boundary_.assign(nc, 0);
  for (int v = 0; v < n_dense_; ++v) {
    gauss_[label[v]] += deficit[v];
    if (dense_boundary[v]) boundary_[label[v]] = 1;
  }
  for (int i = 0; i < nc; ++i) gauss_[i] = area_[i] > 0.0 ? gauss_[i] / area_[i] : 0.0;
  std::vector<Vec3> nsum(nc, Vec3::Zero());
  std::vector<std::pair<int, int>> nbr_pairs;
  for (const Face& f : m.f) {
    const Vec3 av = 0.5 * (m.v[f[1]] - m.v[f[0]]).cross(m.v[f[2]] - m.v[f[0]]);
    for (int j = 0; j < 3; ++j) nsum[label[f[j]]] += av;
    const int a = label[f[0]], b = label[f[1]], c = label[f[2]];
    if (a != b && b != c && a != c) {
      Face t{a, b, c};
      std::sort(t.begin(), t.end());
      tri_.push_back(t);
    }
  }
  for (int v = 0; v < n_dense_; ++v)
    for (int j = g.off[v]; j < g.off[v + 1]; ++j)
      if (label[g.nbr[j]] != label[v]) nbr_pairs.push_back({label[v], label[g.nbr[j]]});
  std::sort(nbr_pairs.begin(), nbr_pairs.end());
  nbr_pairs.erase(std::unique(nbr_pairs.begin(), nbr_pairs.end()), nbr_pairs.end());
  csr(nc, nbr_pairs, &nbr_off_, &nbr_idx_);
  std::sort(tri_.begin(), tri_.end());
  tri_.erase(std::unique(tri_.begin(), tri_.end()), tri_.end());
  std::vector<std::pair<int, int>> fan_pairs;
  for (int t = 0; t < static_cast<int>(tri_.size()); ++t)
    for (int c : tri_[t]) fan_pairs.push_back({c, t});
  csr(nc, fan_pairs, &fan_off_, &fan_idx_);

  nrm_.resize(nc);
  for (int i = 0; i < nc; ++i) {
    const double len = nsum[i].norm();
    // A region folded onto itself (normals cancelling) keeps an arbitrary but unit normal.
    nrm_[i] = len > 0.0 ? Vec3(nsum[i] / len) : Vec3(0.0, 0.0, 1.0);
  }
  tree_ = KdTree3(pos_);
  if (creases.sides > 0) {
    std::vector<int> vertex_side;
    const auto sides = cell_sides(g, m.f, creases, seeds, kCreaseReach * h_, &vertex_side);
    set_sides(m.v, m.f, creases, vertex_side, sides);
  }

  // Input vertex -> the cell triangle around its cell that contains it, else its own cell.
  vcell_.resize(V.rows());
  vweight_.resize(V.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    const int mv = input_to_mesh[i];
    const Vec3 p = V.row(i).transpose();
    const int c = mv >= 0 && mv < n_input_mesh ? label[mv] : nearest(p);
    vcell_[i] = {c, c, c};
    vweight_[i] = {1.0, 0.0, 0.0};
    double best = (p - pos_[c]).norm();
    for (int j = fan_off_[c]; j < fan_off_[c + 1]; ++j) {
      const Face& t = tri_[fan_idx_[j]];
      std::array<double, 3> w;
      const double d = barycentric(p, pos_[t[0]], pos_[t[1]], pos_[t[2]], &w);
      if (d < best - 1e-12 * h_ || (d <= best && best > 0.0 && d == 0.0)) {
        best = d;
        vcell_[i] = t;
        vweight_[i] = w;
      }
    }
  }
}

void SurfaceCells::set_sides(const std::vector<Vec3>& dense, const std::vector<Face>& faces, const Creases& creases,
                             const std::vector<int>& vertex_side, const std::vector<std::pair<int, int>>& cell_sides) {
  sides_ = creases.sides;
  csr(size(), cell_sides, &side_off_, &side_idx_);
  std::vector<Vec3> vertex_normal(dense.size(), Vec3::Zero());
  for (const Face& f : faces) {
    const Vec3 an = (dense[f[1]] - dense[f[0]]).cross(dense[f[2]] - dense[f[0]]);
    for (int v : f) vertex_normal[v] += an;
  }
  std::vector<Vec3> off_crease;
  for (std::size_t v = 0; v < dense.size(); ++v)
    if (!creases.vertex[v] && !creases.sliver[v] && vertex_side[v] >= 0) {
      off_crease.push_back(dense[v]);
      side_vertex_.push_back(vertex_side[v]);
      side_normal_.push_back(vertex_normal[v].normalized());
    }
  side_tree_ = KdTree3(off_crease);
}

int SurfaceCells::side_of(const Eigen::Vector3d& p, Eigen::Vector3d* normal) const {
  if (sides_ == 0 || side_vertex_.empty()) return -1;
  const int v = side_tree_.nearest(p);
  if (normal) *normal = side_normal_[v];
  return side_vertex_[v];
}

bool SurfaceCells::on_side(int c, int s) const {
  if (sides_ == 0 || side_off_[c] == side_off_[c + 1]) return true;
  for (int q = side_off_[c]; q < side_off_[c + 1]; ++q)
    if (side_idx_[q] == s) return true;
  return false;
}

}  // namespace thinburn
