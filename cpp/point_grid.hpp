#pragma once
/// @brief Points in a dense grid of cells, for finding the points near a place: self-contact's
/// candidate pairs (cpp/self_contact.*) and the pyrolysis within its range (cpp/heat.*).
#include <Eigen/Core>

#include <vector>

namespace thinburn {

using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief Points in a dense grid of cells: the points of a cell, and the cells a box covers.
class PointGrid {
 public:
  /// @brief Grid x's rows `points` in cells of `cell` m (doubled while the grid would have
  /// far more cells than points).
  void build(const std::vector<int>& points, const RowMatX3& x, double cell);
  const Eigen::Vector3d& lo() const { return lo_; }  ///< the points' box
  const Eigen::Vector3d& hi() const { return hi_; }
  /// @brief The cells (k0 to k1, inclusive) that the box [a, b] meets, clamped to the grid.
  void range(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Eigen::Array3i& k0, Eigen::Array3i& k1) const;
  const int* begin(int i, int j, int k) const { return items_.data() + start_[cell(i, j, k)]; }
  const int* end(int i, int j, int k) const { return items_.data() + start_[cell(i, j, k) + 1]; }

 private:
  int cell(int i, int j, int k) const { return (i * n_(1) + j) * n_(2) + k; }
  int flat(const Eigen::Vector3d& p) const;
  Eigen::Vector3d lo_, hi_;
  double cell_ = 0.0;
  Eigen::Array3i k_lo_ = Eigen::Array3i::Zero();  // the first cell's index on the lattice of cells
  Eigen::Array3i n_ = Eigen::Array3i::Zero();      // cells per axis
  std::vector<int> start_, fill_, index_, items_;
};

}  // namespace thinburn
