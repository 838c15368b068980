#include "crumple.hpp"

#include <algorithm>
#include <cmath>

#include "lattice.hpp"
#include "threads.hpp"

namespace thinburn {
namespace {

struct Grid {
  int M;
  const RowMatX3& pos;
  Eigen::Vector3d centre(int i, int j) const {
    const int c = i * M + j;
    return 0.5 * (pos.row(2 * c) + pos.row(2 * c + 1)).transpose();
  }
  // Bottom -> top direction of the couple; the in-plane tangents' cross product if the couple
  // has collapsed.
  Eigen::Vector3d normal(int i, int j) const {
    const int c = i * M + j;
    Eigen::Vector3d n = (pos.row(2 * c + 1) - pos.row(2 * c)).transpose();
    if (n.norm() > 1e-300) return n.normalized();
    n = tangent(i, j, true).cross(tangent(i, j, false));
    return n.norm() > 1e-300 ? n.normalized() : Eigen::Vector3d::UnitZ();
  }
  // Centre difference along columns (along_j) or rows, one-sided at the border.
  Eigen::Vector3d tangent(int i, int j, bool along_j) const {
    if (along_j) return centre(i, std::min(j + 1, M - 1)) - centre(i, std::max(j - 1, 0));
    return centre(std::min(i + 1, M - 1), j) - centre(std::max(i - 1, 0), j);
  }
};

// Displacement of point p of the couple whose centre is ca when couple O (centre co, normal n)
// turns it by delta about the line through co along a (in O's tangent plane after projection).
Eigen::Vector3d turn_about(const Eigen::Vector3d& co, const Eigen::Vector3d& n, Eigen::Vector3d a,
                           double delta, const Eigen::Vector3d& ca, const Eigen::Vector3d& p) {
  a -= a.dot(n) * n;
  if (a.norm() <= 1e-300) return Eigen::Vector3d::Zero();
  a.normalize();
  // d/dtheta of a point turned about a is a x r: the sign that moves the neighbour toward +n.
  const double side = a.cross(ca - co).dot(n);
  if (side == 0.0) return Eigen::Vector3d::Zero();
  const double theta = side > 0 ? delta : -delta;
  const Eigen::Vector3d q = p - co;
  const Eigen::Vector3d q_perp = q - q.dot(a) * a;
  return (std::cos(theta) - 1.0) * q_perp + std::sin(theta) * a.cross(q_perp);
}

// Grid: couple (oi, oj) turns its neighbours about its line along columns (along_j) or rows.
Eigen::Vector3d turn(const Grid& g, int oi, int oj, bool along_j, double delta,
                     const Eigen::Vector3d& ca, const Eigen::Vector3d& p) {
  return turn_about(g.centre(oi, oj), g.normal(oi, oj), g.tangent(oi, oj, along_j), delta, ca, p);
}

// Bottom -> top of couple c (+z if it collapsed: a control-surface couple never has zero
// thickness at rest, and the thickness spring is the stiffest).
Eigen::Vector3d couple_axis(const RowMatX3& pos, int c) {
  const Eigen::Vector3d n = (pos.row(2 * c + 1) - pos.row(2 * c)).transpose();
  return n.norm() > 1e-300 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
}

}  // namespace

void crumple_displacements(int M, const RowMatX3& pos, const Eigen::VectorXd& delta,
                           const std::vector<std::uint8_t>& pinned, RowMatX3& out) {
  const Grid g{M, pos};
  const int n = 2 * M * M;
  out.resize(n, 3);
  parallel_for(0, n, 64, [&](long v_) {
    const int v = static_cast<int>(v_);
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    const int c = v / 2, i = c / M, j = c % M;
    if (!pinned[v]) {
      const Eigen::Vector3d ca = g.centre(i, j);
      const Eigen::Vector3d p = pos.row(v).transpose();
      // Neighbours across rows turn about O's line along columns, and vice versa.
      const int di[4] = {-1, 1, 0, 0}, dj[4] = {0, 0, -1, 1};
      for (int q = 0; q < 4; ++q) {
        const int oi = i + di[q], oj = j + dj[q];
        if (oi < 0 || oi >= M || oj < 0 || oj >= M) continue;
        const double dl = delta(oi * M + oj);
        if (dl != 0.0) d += turn(g, oi, oj, /*along_j=*/di[q] != 0, dl, ca, p);
      }
    }
    out.row(v) = d.transpose();
  });
}

void crumple_displacements(const std::vector<int>& nbr_offset, const std::vector<int>& nbr_index,
                           const RowMatX3& pos, const Eigen::VectorXd& delta,
                           const std::vector<std::uint8_t>& pinned, RowMatX3& out) {
  const int n = static_cast<int>(pos.rows());
  out.resize(n, 3);
  parallel_for(0, n, 64, [&](long v_) {
    const int v = static_cast<int>(v_);
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    const int c = v / 2;
    if (!pinned[v]) {
      const Eigen::Vector3d ca = couple_centre(pos, c);
      const Eigen::Vector3d p = pos.row(v).transpose();
      // Every neighbour O of this couple that turns moves it about O's axis perpendicular to O -> c.
      for (int q = nbr_offset[c]; q < nbr_offset[c + 1]; ++q) {
        const int o = nbr_index[q];
        const double dl = delta(o);
        if (dl == 0.0) continue;
        const Eigen::Vector3d co = couple_centre(pos, o), no = couple_axis(pos, o);
        d += turn_about(co, no, no.cross(ca - co), dl, ca, p);
      }
    }
    out.row(v) = d.transpose();
  });
}

}  // namespace thinburn
