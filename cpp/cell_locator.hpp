#pragma once
/// @brief Which cells lie near a 3-D point, for cells that move with the lattice: the cost of
/// an ignite no longer grows with the number of cells.
///
/// Cells are grouped in buckets (the lattice's control cells, or blocks of the grid without a
/// lattice), and a bucket's cells in blocks of at most kBlock x kBlock grid cells. A bucket's
/// cells lie in the box of their rest positions moved by at most its displacement bounds (with
/// the lattice's bilinear embedding the bounds are exact: a cell moves by a convex combination
/// of its four couples' displacements), and so do a block's. A search pops buckets and blocks
/// nearest-box first and stops at the first box farther than the best cell: it costs one box
/// per bucket plus the few blocks near the point, whatever the number of cells.
#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <vector>

#include "lattice.hpp"

namespace thinburn {

class CellLocator {
 public:
  /// @brief Block side, in grid cells.
  static constexpr int kBlock = 8;

  /// @param rest cell rest positions (N*N x 3, row-major grid); @param inside 1 where a cell
  /// is part of the sheet (only those are found); @param bucket_of per cell, its bucket in
  /// [0, buckets).
  CellLocator(int N, const RowMatX3& rest, const std::vector<std::uint8_t>& inside,
              const std::vector<int>& bucket_of, int buckets);

  /// @brief Per bucket, the lowest and highest displacement (buckets x 3) any of its cells has
  /// now. Zero (the default) for cells that never move.
  void set_displacement_bounds(const RowMatX3& lo, const RowMatX3& hi);

  struct Found {
    int nearest = -1;          ///< the nearest inside cell (lowest index among equals), -1 none
    double distance = 0.0;     ///< its distance
    std::vector<int> within;   ///< inside cells within radius, ascending (empty for radius 0)
  };

  /// @brief The nearest cell to `point`, and the cells within `radius`; position(c) gives a
  /// cell's current position.
  Found find(const Eigen::Vector3d& point, double radius,
             const std::function<Eigen::Vector3d(int)>& position) const;

  int buckets() const { return static_cast<int>(block_start_.size()) - 1; }

 private:
  // Distance from p to box `box` (rest_lo_/rest_hi_ rows) moved by bucket b's bounds.
  double box_distance(int box, int b, const Eigen::Vector3d& p) const;

  // Boxes 0..buckets-1 are the buckets; block k is box buckets() + k.
  std::vector<int> block_start_;   // CSR: bucket b holds blocks [block_start_[b], block_start_[b+1])
  std::vector<int> cell_start_;    // CSR: block k holds cells_[cell_start_[k] .. cell_start_[k+1])
  std::vector<int> block_bucket_;  // per block: its bucket
  std::vector<int> cells_;
  RowMatX3 rest_lo_, rest_hi_;     // per box: the box of its cells' rest positions
  RowMatX3 move_lo_, move_hi_;     // per bucket: displacement bounds
};

}  // namespace thinburn
