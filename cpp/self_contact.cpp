#include "self_contact.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "colliders.hpp"

namespace thinburn {
namespace {

// Couples this many rings apart (or closer) never collide: they are one piece of the layer,
// held apart by its springs. The default layer is a quarter of the spacing thick (shell.cpp),
// so two rings are eight separations along the sheet.
constexpr int kRings = 2;
constexpr int kIterations = 4;     // Gauss-Seidel sweeps of the position projection
constexpr double kEdge = 0.05;     // a projection this far (barycentric) past an edge still counts:
                                   // a point over a ridge between two triangles is over neither
// Candidate pairs are found within (1 + kMargin) separations and kept until a couple has moved
// by half of kMargin separations: a sheet moving slowly far from itself rarely looks again.
constexpr double kMargin = 2.0;
// A pair this many separations apart, or closer, at rest is never tested (see narrow_phase).
constexpr double kRestNear = 2.0;


// Barycentric weights of p's projection onto the plane of triangle abc (false: degenerate).
bool barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                 const Eigen::Vector3d& c, double w[3]) {
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
  const double d20 = d.dot(e0), d21 = d.dot(e1);
  const double den = d00 * d11 - d01 * d01;
  if (!(den > 1e-30)) return false;
  w[1] = (d11 * d20 - d01 * d21) / den;
  w[2] = (d00 * d21 - d01 * d20) / den;
  w[0] = 1.0 - w[1] - w[2];
  return true;
}

bool inside(const double w[3]) { return w[0] >= -kEdge && w[1] >= -kEdge && w[2] >= -kEdge; }

// The projection's weights clamped onto the triangle, summing to 1.
void clamp_weights(double w[3]) {
  double sum = 0.0;
  for (int i = 0; i < 3; ++i) sum += (w[i] = std::max(0.0, w[i]));
  for (int i = 0; i < 3; ++i) w[i] /= sum;
}

Eigen::Vector3d unit_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0.0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

}  // namespace

SelfContact::SelfContact(const LatticeTopology& topo, const RowMatX3& rest) : C_(topo.couples) {
  if (rest.rows() != 2 * C_) throw std::invalid_argument("self contact: rest must have 2 rows per couple");
  rest_mid_.resize(C_, 3);
  for (int c = 0; c < C_; ++c) {
    thickness_ += (rest.row(2 * c + 1) - rest.row(2 * c)).norm();
    rest_mid_.row(c) = 0.5 * (rest.row(2 * c) + rest.row(2 * c + 1));
  }
  thickness_ /= std::max(1, C_);
  const auto& off = topo.nbr_offset;
  const auto& nb = topo.nbr_index;
  if (topo.grid_side > 0) {
    const int M = topo.grid_side;
    for (int i = 0; i + 1 < M; ++i)
      for (int j = 0; j + 1 < M; ++j) {
        const int c00 = i * M + j, c10 = c00 + M, c01 = c00 + 1, c11 = c10 + 1;
        tri_.emplace_back(c00, c10, c11);
        tri_.emplace_back(c00, c11, c01);
      }
  } else {
    // A control surface: its triangulation's edges are the neighbour graph's; each triangle
    // is a triple of mutual neighbours, listed once (a < b < c).
    for (int a = 0; a < C_; ++a)
      for (int p = off[a]; p < off[a + 1]; ++p) {
        const int b = nb[p];
        if (b <= a) continue;
        for (int q = off[b]; q < off[b + 1]; ++q) {
          const int c = nb[q];
          if (c <= b) continue;
          if (std::find(nb.begin() + off[a], nb.begin() + off[a + 1], c) != nb.begin() + off[a + 1])
            tri_.emplace_back(a, b, c);
        }
      }
  }
  // Rings: breadth-first over the neighbour graph from each couple.
  std::vector<int> stamp(C_, -1), frontier, next;
  ring_start_.assign(1, 0);
  for (int c = 0; c < C_; ++c) {
    const std::size_t first = ring_.size();
    frontier.assign(1, c);
    stamp[c] = c;
    ring_.push_back(c);
    for (int r = 0; r < kRings; ++r) {
      next.clear();
      for (int u : frontier)
        for (int p = off[u]; p < off[u + 1]; ++p)
          if (stamp[nb[p]] != c) {
            stamp[nb[p]] = c;
            next.push_back(nb[p]);
            ring_.push_back(nb[p]);
          }
      frontier.swap(next);
    }
    std::sort(ring_.begin() + first, ring_.end());
    ring_start_.push_back(static_cast<int>(ring_.size()));
  }
  // Hash cells of the rest spacing: a triangle then spans a few cells, a point one.
  double edges = 0.0;
  for (const auto& t : tri_)
    for (int e = 0; e < 3; ++e) {
      const Eigen::Vector3d a = 0.5 * (rest.row(2 * t(e)) + rest.row(2 * t(e) + 1)).transpose();
      const Eigen::Vector3d b = 0.5 * (rest.row(2 * t((e + 1) % 3)) + rest.row(2 * t((e + 1) % 3) + 1)).transpose();
      edges += (b - a).norm();
    }
  cell_ = tri_.empty() ? 1.0 : edges / (3.0 * tri_.size());
  if (!(cell_ > 0.0)) cell_ = 1.0;
}

bool SelfContact::neighbours(int c, const Eigen::Vector3i& t) const {
  for (int i = 0; i < 3; ++i)
    if (std::binary_search(ring_.begin() + ring_start_[t(i)], ring_.begin() + ring_start_[t(i) + 1], c))
      return true;
  return false;
}

int SelfContact::apply(double sep, RowMatX3& x, RowMatX3& v, const Eigen::VectorXd& mass,
                       const std::vector<int>& slot) {
  moving_.clear();
  for (int c = 0; c < C_; ++c)
    if (slot[2 * c] >= 0 && slot[2 * c + 1] >= 0) moving_.push_back(c);
  if (moving_.empty() || tri_.empty() || !(sep > 0.0)) return 0;
  if (last_.rows() != C_) {
    last_.resize(C_, 3);
    for (int c = 0; c < C_; ++c) last_.row(c) = couple_centre(x, c).transpose();
  }
  if (!broad_valid(sep, x)) broad_phase(sep, x);
  pairs_.clear();
  if (!candidates_.empty()) narrow_phase(sep, x, v, mass);
  if (!pairs_.empty()) {
    sep_ = sep;
    project();
    stop_approach();
    for (int c : involved_) {
      if (inv_(c) == 0.0) continue;
      const double m0 = mass(2 * c), m1 = mass(2 * c + 1);
      const Eigen::RowVector3d dx = mid_.row(c) - couple_centre(x, c).transpose();
      const Eigen::RowVector3d dv = vmid_.row(c) - (m0 * v.row(2 * c) + m1 * v.row(2 * c + 1)) * inv_(c);
      for (int k = 0; k < 2; ++k) {
        x.row(2 * c + k) += dx;
        v.row(2 * c + k) += dv;
      }
    }
  }
  for (int c : moving_) last_.row(c) = couple_centre(x, c).transpose();
  return static_cast<int>(pairs_.size());
}

bool SelfContact::broad_valid(double sep, const RowMatX3& x) const {
  if (broad_.rows() != C_ || broad_sep_ != sep) return false;
  const double half = 0.5 * kMargin * sep;
  for (int c : moving_)  // one that woke since was not hashed: its pairs are not candidates
    if (!broad_moving_[c] || (couple_centre(x, c) - broad_.row(c).transpose()).squaredNorm() >= half * half) return false;
  return true;
}

void SelfContact::broad_phase(double sep, const RowMatX3& x) {
  // Every (moving couple, triangle) pair within sep + margin now, as point to the triangle's
  // box: until a couple moves by half the margin, no other pair can come within sep.
  broad_.resize(C_, 3);
  for (int c = 0; c < C_; ++c) broad_.row(c) = couple_centre(x, c).transpose();
  broad_sep_ = sep;
  broad_moving_.assign(C_, 0);
  for (int c : moving_) broad_moving_[c] = 1;
  candidates_.clear();
  const double reach = (1.0 + kMargin) * sep;
  const auto at = [&](int c) { return Eigen::Vector3d(broad_.row(c).transpose()); };
  grid_.build(moving_, broad_, cell_);
  Eigen::Vector3d lo = grid_.lo(), hi = grid_.hi();
  lo.array() -= reach;
  hi.array() += reach;
  constexpr int kMaxCells = 4096;  // a triangle stretched over more cells than this is skipped
  for (int t = 0; t < static_cast<int>(tri_.size()); ++t) {
    const Eigen::Vector3i& T = tri_[t];
    const Eigen::Vector3d A = at(T(0)), B = at(T(1)), Cc = at(T(2));
    const Eigen::Vector3d blo = A.cwiseMin(B).cwiseMin(Cc), bhi = A.cwiseMax(B).cwiseMax(Cc);
    const Eigen::Vector3d tlo = blo.array() - reach, thi = bhi.array() + reach;
    if ((tlo.array() > hi.array()).any() || (thi.array() < lo.array()).any()) continue;
    Eigen::Array3i k0, k1;
    grid_.range(tlo, thi, k0, k1);
    if (double(k1(0) - k0(0) + 1) * (k1(1) - k0(1) + 1) * (k1(2) - k0(2) + 1) > kMaxCells) continue;
    for (int i = k0(0); i <= k1(0); ++i)
      for (int j = k0(1); j <= k1(1); ++j)
        for (int k = k0(2); k <= k1(2); ++k)
          for (const int* it = grid_.begin(i, j, k), *e = grid_.end(i, j, k); it != e; ++it) {
            const int c = *it;
            const Eigen::Vector3d P = at(c);
            const Eigen::Vector3d out = (blo - P).cwiseMax(P - bhi).cwiseMax(0.0);
            if (out.squaredNorm() >= reach * reach || neighbours(c, T)) continue;
            candidates_.emplace_back(c, t);
          }
  }
}

void SelfContact::narrow_phase(double sep, const RowMatX3& x, const RowMatX3& v, const Eigen::VectorXd& mass) {
  // The candidates' couples: mid-points, velocities and inverse masses (0: not moving).
  if (static_cast<int>(is_involved_.size()) != C_) {
    is_involved_.assign(C_, 0);
    inv_.resize(C_);
    mid_.resize(C_, 3);
    vmid_.resize(C_, 3);
  }
  involved_.clear();
  const auto involve = [&](int c) {
    if (is_involved_[c]) return;
    is_involved_[c] = 1;
    involved_.push_back(c);
    mid_.row(c) = couple_centre(x, c).transpose();
    inv_(c) = 0.0;
    vmid_.row(c).setZero();
  };
  for (const auto& [c, t] : candidates_) {
    involve(c);
    for (int i = 0; i < 3; ++i) involve(tri_[t](i));
  }
  for (int c : moving_)
    if (is_involved_[c]) {
      const double m0 = mass(2 * c), m1 = mass(2 * c + 1);
      inv_(c) = 1.0 / (m0 + m1);
      vmid_.row(c) = (m0 * v.row(2 * c) + m1 * v.row(2 * c + 1)) * inv_(c);
    }
  for (int c : involved_) is_involved_[c] = 0;
  const auto at = [&](const RowMatX3& m, int c) { return Eigen::Vector3d(m.row(c).transpose()); };
  for (const auto& [c, t] : candidates_) {
    const Eigen::Vector3i& T = tri_[t];
    const Eigen::Vector3d A = at(mid_, T(0)), B = at(mid_, T(1)), Cc = at(mid_, T(2)), P = at(mid_, c);
    const Eigen::Vector3d n = unit_normal(A, B, Cc);
    if (n.squaredNorm() == 0.0) continue;
    // A point may have crossed the triangle since the previous apply: look as far as the pair
    // travelled.
    const Eigen::Vector3d A0 = at(last_, T(0)), B0 = at(last_, T(1)), C0 = at(last_, T(2)), P0 = at(last_, c);
    const double travel = (P - P0).norm() + std::max({(A - A0).norm(), (B - B0).norm(), (Cc - C0).norm()});
    const double s = (P - A).dot(n);
    if (std::abs(s) >= sep + travel) continue;
    Pair pr{c, t, {0, 0, 0}, 0.0};
    if (!barycentric(P, A, B, Cc, pr.b) || !inside(pr.b)) continue;
    // The side: where the point was after the previous projection.
    const double s0 = (P0 - A0).dot(unit_normal(A0, B0, C0));
    pr.side = s0 > 0.0 ? 1.0 : s0 < 0.0 ? -1.0 : (s >= 0.0 ? 1.0 : -1.0);
    if (pr.side * s >= sep) continue;
    if (pr.side * s < 0.0) {
      // It crossed the plane: through the triangle, where the straight paths of point and
      // triangle meet the plane, or around an edge (then it is not this triangle's).
      const double u = std::clamp(s0 / (s0 - s), 0.0, 1.0);  // s0 and s have opposite signs
      const auto lerp = [&](const Eigen::Vector3d& p0, const Eigen::Vector3d& p1) {
        return Eigen::Vector3d(p0 + u * (p1 - p0));
      };
      double w[3];
      if (!barycentric(lerp(P0, P), lerp(A0, A), lerp(B0, B), lerp(C0, Cc), w) || !inside(w)) continue;
    }
    clamp_weights(pr.b);
    // Parts of the sheet modelled near each other (sheets stacked 4 mm apart in a 10 mm thick
    // lattice) are left to the springs: pushed apart to the separation, they tore.
    const Eigen::Vector3d Pr = at(rest_mid_, c);
    const double rest_gap = (Pr - closest_on_triangle(Pr, at(rest_mid_, T(0)), at(rest_mid_, T(1)), at(rest_mid_, T(2)))).norm();
    if (rest_gap < kRestNear * sep) continue;
    pairs_.push_back(pr);
  }
}

void SelfContact::project() {
  const auto row = [&](int c) { return Eigen::Vector3d(mid_.row(c).transpose()); };
  for (int it = 0; it < kIterations; ++it) {
    bool moved = false;
    for (const Pair& pr : pairs_) {
      const Eigen::Vector3i& T = tri_[pr.tri];
      const Eigen::Vector3d n = pr.side * unit_normal(row(T(0)), row(T(1)), row(T(2)));
      const Eigen::Vector3d Q = pr.b[0] * row(T(0)) + pr.b[1] * row(T(1)) + pr.b[2] * row(T(2));
      const double g = (row(pr.point) - Q).dot(n);
      if (g >= sep_ || n.squaredNorm() == 0.0) continue;
      double den = inv_(pr.point);
      for (int i = 0; i < 3; ++i) den += pr.b[i] * pr.b[i] * inv_(T(i));
      if (!(den > 0.0)) continue;
      const double lambda = (sep_ - g) / den;
      mid_.row(pr.point) += (inv_(pr.point) * lambda) * n.transpose();
      for (int i = 0; i < 3; ++i) mid_.row(T(i)) -= (pr.b[i] * inv_(T(i)) * lambda) * n.transpose();
      moved = true;
    }
    if (!moved) break;
  }
}

void SelfContact::stop_approach() {
  const auto row = [&](int c) { return Eigen::Vector3d(mid_.row(c).transpose()); };
  for (int it = 0; it < 2; ++it)
    for (const Pair& pr : pairs_) {
      const Eigen::Vector3i& T = tri_[pr.tri];
      const Eigen::Vector3d n = pr.side * unit_normal(row(T(0)), row(T(1)), row(T(2)));
      Eigen::Vector3d rel = vmid_.row(pr.point).transpose();
      for (int i = 0; i < 3; ++i) rel -= pr.b[i] * vmid_.row(T(i)).transpose();
      const double vn = rel.dot(n);
      if (vn >= 0.0) continue;
      double den = inv_(pr.point);
      for (int i = 0; i < 3; ++i) den += pr.b[i] * pr.b[i] * inv_(T(i));
      if (!(den > 0.0)) continue;
      const double mu = -vn / den;
      vmid_.row(pr.point) += (inv_(pr.point) * mu) * n.transpose();
      for (int i = 0; i < 3; ++i) vmid_.row(T(i)) -= (pr.b[i] * inv_(T(i)) * mu) * n.transpose();
    }
}

}  // namespace thinburn
