#pragma once
/// @brief Heat (Liu et al. 2009 eq 2) and pyrolysis (eq 3) as kernel sums, direct or fast.
///
/// Both are S(y) = sum_i w_i K(|y - x_i|) with K(d) = (d + d_min)^-p, w_i >= 0: p = 2 for the
/// heat of fire particles, p = 1 for the pyrolysis of ignition points. The fast method is a
/// Barnes-Hut octree with a third-order Taylor expansion (weight, second and third moments)
/// about each cell's weighted centroid and a fourth-order remainder bound, opened so that
/// every target's sum is within `tolerance` relative error of the direct sum (a proven
/// bound, see docs/heat.md).
#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace thinburn {

using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief How a kernel sum is evaluated.
enum class SumMethod { Direct, Fast };

/// @brief Options of a kernel sum.
struct KernelSumOptions {
  int power = 2;                         ///< p in K(d) = (d + d_min)^-p; 1 or 2
  double d_min = 0.01;                   ///< m, > 0: keeps K finite at d = 0
  SumMethod method = SumMethod::Fast;    ///< Direct: all pairs; Fast: octree
  double tolerance = 0.01;               ///< relative error bound of Fast, in (0, 1)
  /// m, >= 0. 0: the kernel reaches everywhere. > 0: K(d) - K(cutoff) within the cutoff, 0
  /// beyond, summed exactly over the sources within it (a grid of cells of `cutoff`; method
  /// and tolerance are not used). The constant K(cutoff) cancels from the difference between
  /// two targets for every source within the cutoff of both, so the difference keeps their
  /// near field (eq 3's D: a couple's top and bottom) and drops only the far sources.
  double cutoff = 0.0;
};

/// @brief Validate options; throws std::invalid_argument naming the field.
void validate(const KernelSumOptions& opt);

namespace detail {
/// @brief A node of KernelSummer's octree: a contiguous range of the reordered sources.
struct KernelNode {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< weighted centroid
  double weight = 0.0;                      ///< sum of weights (> 0)
  double radius = 0.0;                      ///< max distance from centre to a source
  double q[6] = {0, 0, 0, 0, 0, 0};         ///< sum w d d^T, d = x - centre: xx yy zz xy xz yz
  double t[10] = {0, 0, 0, 0, 0, 0, 0, 0, 0, 0};  ///< sum w d d d: xxx yyy zzz xxy xxz xyy yyz xzz yzz xyz
  double m4 = 0.0;                          ///< sum w |d|^4
  int begin = 0, end = 0;                   ///< range of the reordered sources
  int first_child = -1, child_count = 0;    ///< children are contiguous
};
}  // namespace detail

/// @brief An octree over weighted sources, built once and evaluated at many targets.
///
/// Holds its buffers between calls: rebuild with new sources without reallocating when the
/// source count does not grow.
class KernelSummer {
 public:
  /// @brief Build the tree over sources (n x 3) with weights w (n, finite, >= 0).
  void build(const RowMatX3& sources, const Eigen::VectorXd& w);

  /// @brief out(j) = sum_i w(i) / (|targets(j) - sources(i)| + d_min)^power.
  /// @param error_bound if not null, receives a per-target bound on |out(j) - exact(j)|
  ///        (absolute; zero for Direct). For Fast it is <= tolerance * exact(j).
  /// Parallel over targets; every target's sum runs in a fixed order, so the result is
  /// bit-identical for any thread count.
  void evaluate(const RowMatX3& targets, const KernelSumOptions& opt, Eigen::VectorXd& out,
                Eigen::VectorXd* error_bound = nullptr) const;

  /// @brief Number of sources in the tree.
  Eigen::Index size() const { return Eigen::Index(raw_w_.size()); }
  /// @brief Number of tree nodes.
  std::size_t node_count() const { return nodes_.size(); }

 private:
  void split(int idx, const Eigen::Vector3d& centre, double half, int depth);
  void moments(detail::KernelNode& node) const;

  // std::vector rather than Eigen so that rebuilding with fewer sources keeps the storage.
  std::vector<double> xs_;      // sources with w > 0, in tree order, xyz interleaved
  std::vector<double> ws_;      // their weights
  std::vector<double> raw_x_;   // all sources in input order (Direct), xyz interleaved
  std::vector<double> raw_w_;   // all weights in input order (Direct)
  std::vector<double> raw_tmp_x_, raw_tmp_w_;  // permutation scratch
  std::vector<int> order_, scratch_;
  std::vector<unsigned char> octant_;
  std::vector<detail::KernelNode> nodes_;
  double total_weight_ = 0.0;
};

/// @brief out(j) = sum_i w(i) / (|targets(j) - sources(i)| + d_min)^power, direct or fast (or
/// truncated at opt.cutoff).
/// @param error_bound if not null, a per-target bound on |out(j) - exact(j)| (absolute).
/// Fast reuses a per-thread KernelSummer's buffers across calls.
void kernel_sum(const RowMatX3& sources, const Eigen::VectorXd& w, const RowMatX3& targets,
                const KernelSumOptions& opt, Eigen::VectorXd& out,
                Eigen::VectorXd* error_bound = nullptr);

/// @brief Heat received in one step by each vertex from particles, eq (2):
/// out(j) = Ct * dt / (4 pi) * sum_A T_A / (d_AB + d_min)^2. opt.power must be 2.
void particle_heat(const RowMatX3& particles, const Eigen::VectorXd& temperature,
                   const RowMatX3& vertices, double ct, double dt, const KernelSumOptions& opt,
                   Eigen::VectorXd& out, Eigen::VectorXd* error_bound = nullptr);

/// @brief Pyrolysis of each vertex from ignition points, eq (3):
/// out(j) = Cp * sum_i 1 / (dis_ij + d_min). opt.power must be 1.
void pyrolysis(const RowMatX3& ignition_points, const RowMatX3& vertices, double cp,
               const KernelSumOptions& opt, Eigen::VectorXd& out,
               Eigen::VectorXd* error_bound = nullptr);

}  // namespace thinburn
