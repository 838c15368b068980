#include "control_surface.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "threads.hpp"

namespace thinburn {
namespace {

constexpr int kRings = 4;            // candidate couples: this many rings of the nearest one
constexpr double kWindow = 2.0;      // window radius R in spacings: 11-15 couples inside (1.5 left ill-conditioned weights: 27 degree kinks)
constexpr long kPointCost = 24;      // one point's deform, in kParallelWork units
constexpr int kS = SurfaceEmbedding::kStencil;
// Ridge on the MLS's normal term, per unit window: couples spread across the normal by more
// than about sqrt(kNormalRidge) R make the weights reproduce linear fields in 3-D.
constexpr double kNormalRidge = 1e-4;

// Wendland's C2 window: 1 at q = 0, 0 with zero first and second derivatives at q = 1.
double wendland(double q) {
  if (q >= 1.0) return 0.0;
  const double a = 1.0 - q;
  return a * a * a * a * (4.0 * q + 1.0);
}

Eigen::Vector3d mid(const RowMatX3& x, int c) { return 0.5 * (x.row(2 * c) + x.row(2 * c + 1)).transpose(); }
Eigen::Vector3d axis(const RowMatX3& x, int c) { return (x.row(2 * c + 1) - x.row(2 * c)).transpose(); }

// Per couple, the couples an edge joins it to.
std::vector<std::vector<int>> neighbour_lists(const std::map<std::pair<int, int>, std::vector<int>>& edges, int C) {
  std::vector<std::vector<int>> nbr(C);
  for (const auto& [e, opp] : edges) {
    nbr[e.first].push_back(e.second);
    nbr[e.second].push_back(e.first);
  }
  return nbr;
}

}  // namespace

ControlSurface::ControlSurface(const SurfVerts& vertices, const SurfFaces& faces, double spacing,
                               double thickness, double crease_angle)
    : thickness_(thickness) {
  if (!(spacing > 0) || !std::isfinite(spacing)) throw std::invalid_argument("lattice: the couples' spacing must be > 0");
  if (!(thickness > 0) || !std::isfinite(thickness)) throw std::invalid_argument("lattice_thickness must be > 0");
  if (!(crease_angle >= 0 && crease_angle <= 180))
    throw std::invalid_argument("crease_angle must be within [0, 180] degrees");
  CellOptions opt;
  opt.spacing = spacing;
  // Couples on the rim: a mesh point beyond the outermost couples was extrapolated from them,
  // and the lever turned their twist into stretch (a pleated curtain's side edge in wind:
  // single edges 2.3x; docs/lattice.md, "Rim couples").
  opt.rim_seeds = true;
  // A crease_angle of 180 (or more than any edge turns) leaves the shell without creases.
  opt.crease_angle = crease_angle < 180 ? crease_angle * 3.14159265358979323846 / 180.0 : 0.0;
  coarse_ = std::make_shared<const SurfaceCells>(vertices, faces, opt);
  const int C = coarse_->size();
  if (C < 3)
    throw std::invalid_argument("lattice: only " + std::to_string(C) +
                                " couples fit on this shell; use a finer lattice (more couples per side)");
  rest_.resize(2 * C, 3);
  for (int c = 0; c < C; ++c) {
    const Eigen::Vector3d p = coarse_->positions()[c], n = coarse_->normals()[c];
    rest_.row(2 * c) = (p - 0.5 * thickness_ * n).transpose();
    rest_.row(2 * c + 1) = (p + 0.5 * thickness_ * n).transpose();
  }
  build_topology();
}

void ControlSurface::tie_loose_couples(std::map<std::pair<int, int>, std::vector<int>>& edges) const {
  // A couple tied to one other only (a sheet's corner whose region touches the region inside it
  // and no other: it happens on a regular grid as rounding breaks the sampling's ties) turns
  // freely about that one: the crumple folded a letter's lit corner shut onto the next couple
  // along its edge, its paper to 0.08x. It is tied to the two nearest of its neighbour's
  // neighbours as well (the same piece), which makes it the corner of two triangles.
  const int C = coarse_->size();
  const std::vector<std::vector<int>> nbr = neighbour_lists(edges, C);
  const auto& pos = coarse_->positions();
  for (int c = 0; c < C; ++c) {
    if (nbr[c].size() != 1) continue;
    std::vector<std::pair<double, int>> near;
    for (int o : nbr[nbr[c][0]])
      if (o != c) near.push_back({(pos[o] - pos[c]).squaredNorm(), o});
    std::sort(near.begin(), near.end());
    for (std::size_t k = 0; k < near.size() && k < 2; ++k)
      edges.try_emplace({std::min(c, near[k].second), std::max(c, near[k].second)});
  }
}

void ControlSurface::build_topology() {
  // Edges of the control surface's triangles, each once, ascending; and per edge the corners
  // opposite it (two on an interior edge: a flex spring between them).
  const int C = coarse_->size();
  std::map<std::pair<int, int>, std::vector<int>> edges;
  for (const auto& t : coarse_->triangles())
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}].push_back(t[(k + 2) % 3]);
    }
  // Neighbouring regions that share no control triangle (a strip one triangle wide, a rim)
  // are joined too: an edge with no opposite corner.
  const auto& off = coarse_->nbr_offset();
  const auto& idx = coarse_->nbr_index();
  for (int c = 0; c < C; ++c)
    for (int q = off[c]; q < off[c + 1]; ++q)
      if (idx[q] != c) edges.try_emplace({std::min(c, idx[q]), std::max(c, idx[q])});
  tie_loose_couples(edges);
  std::vector<std::pair<int, int>> flex;
  for (const auto& [e, opp] : edges)
    if (opp.size() == 2 && opp[0] != opp[1]) flex.push_back({std::min(opp[0], opp[1]), std::max(opp[0], opp[1])});
  std::sort(flex.begin(), flex.end());
  flex.erase(std::unique(flex.begin(), flex.end()), flex.end());

  topo_ = LatticeTopology{};
  topo_.couples = C;
  auto add = [this](int a, int b, std::uint8_t kind) {
    topo_.spring_a.push_back(a);
    topo_.spring_b.push_back(b);
    topo_.kind.push_back(kind);
  };
  for (int k = 0; k < 2; ++k) {
    for (const auto& [e, opp] : edges) add(2 * e.first + k, 2 * e.second + k, 0);
    for (const auto& f : flex) add(2 * f.first + k, 2 * f.second + k, 2);
  }
  for (int c = 0; c < C; ++c) add(2 * c, 2 * c + 1, 3);
  for (const auto& [e, opp] : edges) {
    add(2 * e.first, 2 * e.second + 1, 4);
    add(2 * e.first + 1, 2 * e.second, 4);
  }
  std::vector<std::vector<int>> nbr = neighbour_lists(edges, C);
  topo_.nbr_offset.assign(1, 0);
  for (int c = 0; c < C; ++c) {
    if (nbr[c].empty())
      throw std::invalid_argument("lattice: couple " + std::to_string(c) +
                                  " of the control surface has no neighbour (a piece too small for the "
                                  "lattice's spacing); use a finer lattice");
    std::sort(nbr[c].begin(), nbr[c].end());
    topo_.nbr_index.insert(topo_.nbr_index.end(), nbr[c].begin(), nbr[c].end());
    topo_.nbr_offset.push_back(static_cast<int>(topo_.nbr_index.size()));
  }
}

double ControlSurface::edge_curvature(double quantile) const {
  // Per couple, its most curved edge (a cylinder's edges round it, not those along it); then
  // the quantile over couples, so a crease (a few couples) does not count as a curve.
  const auto& pos = coarse_->positions();
  const auto& nrm = coarse_->normals();
  const int C = topo_.couples;
  std::vector<double> k(C, 0.0);
  for (int c = 0; c < C; ++c)
    for (int q = topo_.nbr_offset[c]; q < topo_.nbr_offset[c + 1]; ++q) {
      const int o = topo_.nbr_index[q];
      const double len = (pos[c] - pos[o]).norm();
      if (len > 0) k[c] = std::max(k[c], std::acos(std::clamp(nrm[c].dot(nrm[o]), -1.0, 1.0)) / len);
    }
  if (k.empty()) return 0.0;
  const std::size_t at = std::min(k.size() - 1, static_cast<std::size_t>(quantile * (k.size() - 1)));
  std::nth_element(k.begin(), k.begin() + at, k.end());
  return k[at];
}

void ControlSurface::gather(int start, std::vector<int>& out, std::vector<int>& stamp, int& id) const {
  // The couples within kRings edges of `start`, breadth-first.
  ++id;
  out.assign(1, start);
  stamp[start] = id;
  std::size_t ring_begin = 0;
  for (int ring = 0; ring < kRings; ++ring) {
    const std::size_t ring_end = out.size();
    for (std::size_t q = ring_begin; q < ring_end; ++q)
      for (int j = topo_.nbr_offset[out[q]]; j < topo_.nbr_offset[out[q] + 1]; ++j) {
        const int o = topo_.nbr_index[j];
        if (stamp[o] == id) continue;
        stamp[o] = id;
        out.push_back(o);
      }
    ring_begin = ring_end;
  }
}

void ControlSurface::keep_side(int side, std::vector<int>& cand) const {
  // Across a crease the two sides turn independently: a window mixing their couples bent the
  // sheet near the fold (a folded letter's edges within 1 cm of it: 1.8-2.1 % at 40 s, p99).
  // A point with fewer than 3 couples of its side in its rings keeps them all.
  if (side < 0) return;
  std::vector<int> own;
  for (int c : cand)
    if (coarse_->on_side(c, side)) own.push_back(c);
  if (own.size() >= 3) cand.swap(own);
}

SurfaceEmbedding ControlSurface::embed(const RowMatX3& points, const std::vector<int>& seeds) const {
  if (!points.allFinite()) throw std::invalid_argument("points must be finite");
  if (!seeds.empty() && seeds.size() != static_cast<std::size_t>(points.rows()))
    throw std::invalid_argument("seeds: one couple per point expected");
  const Eigen::Index n = points.rows();
  SurfaceEmbedding e;
  e.couple.assign(std::size_t(n) * kS, 0);
  e.weight.assign(std::size_t(n) * kS, 0.0);
  e.share.assign(std::size_t(n) * kS, 0.0);
  e.rest = points;
  e.rest_normal.resize(n, 3);
  e.offset.resize(n);
  const auto& pos = coarse_->positions();
  const auto& nrm = coarse_->normals();
  const double R0 = kWindow * coarse_->spacing();
  std::vector<int> stamp(coarse_->size(), 0), cand;
  int id = 0;
  std::vector<std::pair<double, int>> win;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d x = points.row(i).transpose();
    const int c0 = seeds.empty() || seeds[i] < 0 || seeds[i] >= coarse_->size() ? coarse_->nearest(x) : seeds[i];
    gather(c0, cand, stamp, id);
    Eigen::Vector3d side_normal;
    const int side = coarse_->side_of(x, &side_normal);
    keep_side(side, cand);
    // Widen the window until three couples see the point (a point far out at a piece's rim).
    double R = R0;
    for (int tries = 0; tries < 4; ++tries, R *= 1.5) {
      win.clear();
      for (int c : cand) {
        const double phi = wendland((pos[c] - x).norm() / R);
        if (phi > 0.0) win.push_back({phi, c});
      }
      if (win.size() >= 3) break;
    }
    if (win.empty()) win.push_back({1.0, c0});
    // The kS largest windows (a point never sees more on a shell of even cells; if it does,
    // the smallest windows, near zero at the rim, are dropped).
    std::sort(win.begin(), win.end(), [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
    if (win.size() > static_cast<std::size_t>(kS)) win.resize(kS);
    double total = 0.0;
    Eigen::Vector3d nx = Eigen::Vector3d::Zero();
    for (const auto& [phi, c] : win) {
      total += phi;
      nx += phi * nrm[c];
    }
    nx = nx.norm() > 0 ? Eigen::Vector3d(nx.normalized()) : nrm[c0];
    // Near a crease the couples on it carry the fold's mean normal: the MLS's frame takes the
    // side's own (its tangent plane is where the fit is linear, the normal term ridged).
    if (side >= 0) nx = side_normal;
    // Linear MLS: w_k = phi_k [1 0 0 0] A^-1 p_k, p_k = (1, t1.d_k, t2.d_k, n.d_k) / R with d_k =
    // y_k - x in x's frame (t1, t2, n), A = sum phi_k p_k p_k^T + ridge on the normal term. Where
    // the couples spread across the normal (a curve, a crease) the weights reproduce any linear
    // field in 3-D, so a turning or tumbling shell moves rigidly; on a flat patch the ridge leaves
    // the tangent-plane MLS. Shepard's weights where even that is singular (collinear couples).
    const Eigen::Vector3d t1 = nx.unitOrthogonal(), t2 = nx.cross(t1);
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    std::vector<Eigen::Vector4d> pk(win.size());
    for (std::size_t q = 0; q < win.size(); ++q) {
      const Eigen::Vector3d d = (pos[win[q].second] - x) / R;
      pk[q] = Eigen::Vector4d(1.0, d.dot(t1), d.dot(t2), d.dot(nx));
      A += win[q].first * pk[q] * pk[q].transpose();
    }
    A(3, 3) += kNormalRidge * total;
    const Eigen::FullPivLU<Eigen::Matrix4d> lu(A);
    const bool mls = win.size() >= 3 && lu.rcond() > 1e-10;
    const Eigen::Vector4d row = mls ? Eigen::Vector4d(lu.solve(Eigen::Vector4d::UnitX())) : Eigen::Vector4d::Zero();
    Eigen::Vector3d mid0 = Eigen::Vector3d::Zero(), n0 = Eigen::Vector3d::Zero();
    for (std::size_t q = 0; q < win.size(); ++q) {
      const std::size_t slot = std::size_t(i) * kS + q;
      const int c = win[q].second;
      e.couple[slot] = c;
      e.share[slot] = win[q].first / total;
      e.weight[slot] = mls ? win[q].first * row.dot(pk[q]) : e.share[slot];
      mid0 += e.weight[slot] * mid(rest_, c);
      n0 += e.weight[slot] * axis(rest_, c);
    }
    n0 = n0.norm() > 0 ? Eigen::Vector3d(n0.normalized()) : nx;
    e.rest_normal.row(i) = n0.transpose();
    e.offset(i) = (x - mid0).dot(n0);
  }
  return e;
}

Eigen::Vector3d ControlSurface::normal(const SurfaceEmbedding& e, Eigen::Index i, const RowMatX3& x) const {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int q = 0; q < kS; ++q) {
    const std::size_t slot = std::size_t(i) * kS + q;
    const double w = e.weight[slot];
    if (w != 0.0) n += w * axis(x, e.couple[slot]);
  }
  const double len = n.norm();
  return len > 1e-300 ? Eigen::Vector3d(n / len) : Eigen::Vector3d(e.rest_normal.row(i).transpose());
}

Eigen::Vector3d ControlSurface::point(const SurfaceEmbedding& e, Eigen::Index i, const RowMatX3& x) const {
  // rest + the mid-surface's displacement + the rest offset along the normal, turned with it.
  Eigen::Vector3d p = e.rest.row(i).transpose();
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int q = 0; q < kS; ++q) {
    const std::size_t slot = std::size_t(i) * kS + q;
    const double w = e.weight[slot];
    if (w == 0.0) continue;
    const int c = e.couple[slot];
    p += w * (mid(x, c) - mid(rest_, c));
    n += w * axis(x, c);
  }
  const double len = n.norm();
  if (len > 1e-300) p += e.offset(i) * (n / len - e.rest_normal.row(i).transpose());
  return p;
}

void ControlSurface::deform(const SurfaceEmbedding& e, const RowMatX3& control, RowMatX3& out, double z_min) const {
  if (control.rows() != rest_.rows()) throw std::invalid_argument("control: one row per control vertex expected");
  const Eigen::Index n = e.size();
  out.resize(n, 3);
  parallel_for(0, n, kPointCost, [&](long i) {
    Eigen::Vector3d p = point(e, i, control);
    p.z() = std::max(p.z(), z_min);
    out.row(i) = p.transpose();
  });
}

}  // namespace thinburn
