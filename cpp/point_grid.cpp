#include "point_grid.hpp"

#include <cmath>

namespace thinburn {

void PointGrid::build(const std::vector<int>& points, const RowMatX3& x, double cell) {
  // A dense grid over the points' box, by counting sort: a cell's points in the order given.
  // Looked up directly, where a sorted hash took a binary search per cell of each triangle's
  // box (4.5 % of a film frame late in its burn). Cells double while the grid would have far
  // more cells than points (a sheet whose moving part spans the room).
  lo_ = Eigen::Vector3d::Constant(INFINITY);
  hi_ = -lo_;
  for (int c : points) {
    lo_ = lo_.cwiseMin(x.row(c).transpose());
    hi_ = hi_.cwiseMax(x.row(c).transpose());
  }
  cell_ = cell;
  const double most = 8.0 * static_cast<double>(points.size()) + 4096.0;
  // Cells on the lattice of multiples of cell_ (as the hash before them), so that the cells,
  // and the order in which broad_phase finds its candidates, do not depend on the box.
  for (;;) {
    k_lo_ = (lo_ / cell_).array().floor().cast<int>();
    n_ = (hi_ / cell_).array().floor().cast<int>() - k_lo_ + 1;
    // A non-finite position (a diverged step) puts every point in one cell rather than loop.
    if (points.empty() || !(lo_.allFinite() && hi_.allFinite()) || double(n_(0)) * n_(1) * n_(2) <= most) break;
    cell_ *= 2.0;
  }
  if (points.empty()) n_.setZero();
  if (!points.empty() && !(lo_.allFinite() && hi_.allFinite())) {
    k_lo_.setZero();
    n_.setOnes();
  }
  start_.assign(std::size_t(n_.prod()) + 1, 0);
  index_.resize(points.size());
  for (std::size_t q = 0; q < points.size(); ++q) {
    index_[q] = flat(x.row(points[q]).transpose());
    ++start_[index_[q] + 1];
  }
  for (std::size_t i = 1; i < start_.size(); ++i) start_[i] += start_[i - 1];
  items_.resize(points.size());
  fill_ = start_;
  for (std::size_t q = 0; q < points.size(); ++q) items_[fill_[index_[q]]++] = points[q];
}

int PointGrid::flat(const Eigen::Vector3d& p) const {
  const Eigen::Array3i k = ((p / cell_).array().floor().cast<int>() - k_lo_).min(n_ - 1).max(0);
  return (k(0) * n_(1) + k(1)) * n_(2) + k(2);
}

void PointGrid::range(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Eigen::Array3i& k0, Eigen::Array3i& k1) const {
  // Clamped to the grid first: a box far beyond it would overflow int.
  k0 = ((a.cwiseMax(lo_) / cell_).array().floor().cast<int>() - k_lo_).min(n_ - 1).max(0);
  k1 = ((b.cwiseMin(hi_) / cell_).array().floor().cast<int>() - k_lo_).min(n_ - 1).max(0);
}

}  // namespace thinburn
