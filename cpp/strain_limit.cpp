#include "strain_limit.hpp"

#include <algorithm>
#include <cmath>

namespace thinburn {

namespace {

Eigen::Vector3d centre(const RowMatX3& x, int c) { return 0.5 * (x.row(2 * c) + x.row(2 * c + 1)).transpose(); }

}  // namespace

StrainLimit::StrainLimit(const LatticeTopology& topology, const RowMatX3& rest) {
  // Each in-plane pair of couples has a structure or shear spring on each layer; the top
  // layer's (both ends odd) names it once.
  for (int s = 0; s < topology.springs(); ++s) {
    const int a = topology.spring_a[s], b = topology.spring_b[s];
    if (topology.kind[s] > 1 || a % 2 == 0 || b % 2 == 0) continue;
    ca_.push_back(a / 2);
    cb_.push_back(b / 2);
    rest_.push_back((centre(rest, a / 2) - centre(rest, b / 2)).norm());
  }
  for (const auto& [a, b, c] : grid_corners(topology.grid_side)) {
    Corner k{a, b, c, 0.0};
    k.rest = (centre(rest, k.b) + centre(rest, k.c) - 2.0 * centre(rest, k.a)).norm();
    if (k.rest > 0.0) corner_.push_back(k);
  }
}

int StrainLimit::limit_corner(const Corner& k, double limit, RowMatX3& x, RowMatX3& v, const Eigen::VectorXd& mass,
                              const std::vector<int>& slot) const {
  auto moves = [&](int c) { return slot[2 * c] >= 0 && slot[2 * c + 1] >= 0; };
  if (!moves(k.a) && !moves(k.b) && !moves(k.c)) return 0;
  const Eigen::Vector3d g = centre(x, k.b) + centre(x, k.c) - 2.0 * centre(x, k.a);
  const double l = g.norm();
  if (std::abs(l / k.rest - 1.0) <= limit || !(l > 0.0)) return 0;
  const double inside = (1.0 - kInside) * limit;
  const double target = std::clamp(l, (1.0 - inside) * k.rest, (1.0 + inside) * k.rest);
  auto inv = [&](int c) { return moves(c) ? 1.0 / (mass[2 * c] + mass[2 * c + 1]) : 0.0; };
  // |g| has gradient n at b and c and -2 n at a: the mass-weighted step along it.
  const double wa = inv(k.a), wb = inv(k.b), wc = inv(k.c), den = 4.0 * wa + wb + wc;
  const Eigen::RowVector3d n = (g / l).transpose();
  const double fix = (l - target) / den;
  const double rel = (0.5 * (v.row(2 * k.b) + v.row(2 * k.b + 1) + v.row(2 * k.c) + v.row(2 * k.c + 1)) -
                      (v.row(2 * k.a) + v.row(2 * k.a + 1))).dot(n);
  const double away = (l > target ? std::max(rel, 0.0) : std::min(rel, 0.0)) / den;
  for (int s = 0; s < 2; ++s) {
    x.row(2 * k.a + s) += (2.0 * wa * fix) * n;
    x.row(2 * k.b + s) -= (wb * fix) * n;
    x.row(2 * k.c + s) -= (wc * fix) * n;
    v.row(2 * k.a + s) += (2.0 * wa * away) * n;
    v.row(2 * k.b + s) -= (wb * away) * n;
    v.row(2 * k.c + s) -= (wc * away) * n;
  }
  return 1;
}

int StrainLimit::apply(double limit, RowMatX3& x, RowMatX3& v, const Eigen::VectorXd& mass,
                       const std::vector<int>& slot) {
  auto moves = [&](int c) { return slot[2 * c] >= 0 && slot[2 * c + 1] >= 0; };
  candidates_.clear();
  for (int e = 0; e < size(); ++e) {
    const int a = ca_[e], b = cb_[e];
    if ((moves(a) || moves(b)) && rest_[e] > 0.0) candidates_.push_back(e);
  }
  int first = 0;
  const double inside = (1.0 - kInside) * limit;
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    int corrected = 0;
    // Sweeps run forwards and backwards in turn, so that a correction travels along a chain of
    // pairs either way within one sweep.
    const int n = static_cast<int>(candidates_.size());
    for (int i = 0; i < n; ++i) {
      const int e = candidates_[sweep % 2 == 0 ? i : n - 1 - i];
      const int a = ca_[e], b = cb_[e];
      const Eigen::Vector3d d = centre(x, b) - centre(x, a);
      const double l = d.norm();
      if (std::abs(l / rest_[e] - 1.0) <= limit || !(l > 0.0)) continue;
      // Put back a little inside the bound: a pair left on it is pushed off again by its
      // neighbours' corrections, and the sweeps would crawl towards the bound.
      const double lo = (1.0 - inside) * rest_[e], hi = (1.0 + inside) * rest_[e];
      // A couple that does not move (pinned, asleep, or half of it) has infinite mass.
      const double wa = moves(a) ? 1.0 / (mass[2 * a] + mass[2 * a + 1]) : 0.0;
      const double wb = moves(b) ? 1.0 / (mass[2 * b] + mass[2 * b + 1]) : 0.0;
      const Eigen::Vector3d u = d / l;
      const Eigen::RowVector3d fix = ((l - std::clamp(l, lo, hi)) / (wa + wb)) * u.transpose();  // per unit inverse mass
      // The centres' relative speed along u that drives the pair further out of bounds is
      // taken away, inelastically (momentum kept, no energy made). Adding the displacement over
      // the substep to the velocities instead (position-based dynamics) made a pair left beyond
      // the limit by one call, or a short substep, fling the couples apart in the next.
      const double rel = 0.5 * (v.row(2 * b) + v.row(2 * b + 1) - v.row(2 * a) - v.row(2 * a + 1)).dot(u.transpose());
      const double away = l > hi ? std::max(rel, 0.0) : std::min(rel, 0.0);
      const Eigen::RowVector3d dv = (away / (wa + wb)) * u.transpose();
      for (int k = 0; k < 2; ++k) {
        x.row(2 * a + k) += wa * fix;
        x.row(2 * b + k) -= wb * fix;
        v.row(2 * a + k) += wa * dv;
        v.row(2 * b + k) -= wb * dv;
      }
      ++corrected;
    }
    for (const Corner& k : corner_) corrected += limit_corner(k, limit, x, v, mass, slot);
    if (sweep == 0) first = corrected;
    if (corrected == 0) break;
  }
  return first;
}

}  // namespace thinburn
