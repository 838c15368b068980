#include "cell_locator.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <utility>

namespace thinburn {

CellLocator::CellLocator(int N, const RowMatX3& rest, const std::vector<std::uint8_t>& inside,
                         const std::vector<int>& bucket_of, int buckets) {
  const int n = N * N;
  if (N < 1 || buckets < 1 || rest.rows() != n || bucket_of.size() != std::size_t(n) ||
      inside.size() != std::size_t(n))
    throw std::invalid_argument("CellLocator: N*N rest positions, buckets and inside flags expected");
  // Sort the inside cells by (bucket, block, index): each block then is one run of cells_.
  const int nb = (N + kBlock - 1) / kBlock;
  auto block_key = [&](int c) { return (c / N / kBlock) * nb + (c % N) / kBlock; };
  for (int c = 0; c < n; ++c) {
    if (!inside[c]) continue;
    if (bucket_of[c] < 0 || bucket_of[c] >= buckets) throw std::invalid_argument("CellLocator: bucket out of range");
    cells_.push_back(c);
  }
  std::sort(cells_.begin(), cells_.end(), [&](int a, int b) {
    if (bucket_of[a] != bucket_of[b]) return bucket_of[a] < bucket_of[b];
    if (block_key(a) != block_key(b)) return block_key(a) < block_key(b);
    return a < b;
  });
  block_start_.assign(buckets + 1, 0);
  for (std::size_t k = 0; k < cells_.size(); ++k) {
    const int c = cells_[k];
    const bool first = k == 0 || bucket_of[cells_[k - 1]] != bucket_of[c] || block_key(cells_[k - 1]) != block_key(c);
    if (!first) continue;
    cell_start_.push_back(static_cast<int>(k));
    block_bucket_.push_back(bucket_of[c]);
    ++block_start_[bucket_of[c] + 1];
  }
  cell_start_.push_back(static_cast<int>(cells_.size()));
  for (int b = 0; b < buckets; ++b) block_start_[b + 1] += block_start_[b];
  const int blocks = static_cast<int>(block_bucket_.size());
  const double inf = std::numeric_limits<double>::infinity();
  rest_lo_.setConstant(buckets + blocks, 3, inf);
  rest_hi_.setConstant(buckets + blocks, 3, -inf);
  for (int k = 0; k < blocks; ++k)
    for (int q = cell_start_[k]; q < cell_start_[k + 1]; ++q) {
      const auto r = rest.row(cells_[q]);
      for (const int box : {buckets + k, block_bucket_[k]}) {
        rest_lo_.row(box) = rest_lo_.row(box).cwiseMin(r);
        rest_hi_.row(box) = rest_hi_.row(box).cwiseMax(r);
      }
    }
  move_lo_.setZero(buckets, 3);
  move_hi_.setZero(buckets, 3);
}

void CellLocator::set_displacement_bounds(const RowMatX3& lo, const RowMatX3& hi) {
  if (lo.rows() != buckets() || hi.rows() != buckets())
    throw std::invalid_argument("CellLocator: one displacement bound per bucket expected");
  move_lo_ = lo;
  move_hi_ = hi;
}

double CellLocator::box_distance(int box, int b, const Eigen::Vector3d& p) const {
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = rest_lo_(box, a) + move_lo_(b, a), hi = rest_hi_(box, a) + move_hi_(b, a);
    const double out = std::max({lo - p(a), 0.0, p(a) - hi});
    d2 += out * out;
  }
  // Shrunk by a rounding margin: a position summed in another order may land a hair inside.
  return std::sqrt(d2) * (1.0 - 1e-12) - 1e-15;
}

CellLocator::Found CellLocator::find(const Eigen::Vector3d& point, double radius,
                                     const std::function<Eigen::Vector3d(int)>& position) const {
  Found out;
  using Item = std::pair<double, int>;  // (lower bound, box)
  std::vector<Item> items;
  items.reserve(buckets());
  for (int b = 0; b < buckets(); ++b)
    if (block_start_[b + 1] > block_start_[b]) items.emplace_back(box_distance(b, b, point), b);
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open(std::greater<Item>(), std::move(items));
  double best_d2 = std::numeric_limits<double>::infinity();
  const double r2 = radius * radius;
  while (!open.empty()) {
    const auto [lower, box] = open.top();
    if (lower * lower > best_d2 && !(radius > 0 && lower <= radius)) break;  // nothing nearer is left
    open.pop();
    if (box < buckets()) {
      for (int k = block_start_[box]; k < block_start_[box + 1]; ++k)
        open.emplace(box_distance(buckets() + k, box, point), buckets() + k);
      continue;
    }
    const int k = box - buckets();
    for (int q = cell_start_[k]; q < cell_start_[k + 1]; ++q) {
      const int c = cells_[q];
      const double d2 = (position(c) - point).squaredNorm();
      if (d2 < best_d2 || (d2 == best_d2 && c < out.nearest)) best_d2 = d2, out.nearest = c;
      if (radius > 0 && d2 <= r2) out.within.push_back(c);
    }
  }
  out.distance = std::sqrt(best_d2);
  std::sort(out.within.begin(), out.within.end());
  return out;
}

}  // namespace thinburn
