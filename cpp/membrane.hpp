#pragma once
/// @brief A thin shell's soft bending on the two-layer lattice (docs/dynamics.md §1.1).
///
/// The lattice's top and bottom layers carry parallel springs a thickness h apart, so a pair of
/// them resists stretching with 2k and bending with k h^2 / 2: the ratio of the two is set by
/// the lattice's thickness (about 1 cm), not by the sheet's (0.1 mm), and cloth bends about a
/// thousand times too stiffly. With e_t, e_b the two springs' extensions, the pair's energy
///   k/2 (e_t^2 + e_b^2) = k/4 (e_t + e_b)^2 + k/4 (e_t - e_b)^2
/// is a membrane part (the sum) and a bending part (the difference). Scaling the layer springs
/// to share * k and adding a membrane spring of 2 (1 - share) k between the two couples'
/// centres (the mid-surface) keeps the membrane part (the centre spring stretches by
/// (e_t + e_b) / 2) and scales the bending part by share alone.
///
/// A membrane spring joins four control vertices: couple A = (a, a'), couple B = (b, b') with
/// centres c = (x + x') / 2. Its Jacobian J (with respect to the centres) enters the lattice's
/// system as (1/4) [1 1 -1 -1]^T [1 1 -1 -1] (x) J, which is the sum of two-vertex spring blocks:
/// +J/4 on a-b, a'-b', a-b' and a'-b, and -J/4 on the couples' own a-a' and b-b'. So the solver
/// keeps its per-spring blocks; a pair of couples without top-bottom diagonals between them gets
/// them as springs of zero stiffness (kind 5) that only carry these blocks.
#include <Eigen/Core>

#include <cstdint>
#include <utility>
#include <vector>

#include "lattice.hpp"

namespace thinburn {

/// Spring kind of the zero-stiffness top-bottom diagonals that carry membrane blocks.
constexpr std::uint8_t kPatternSpring = 5;

/// @brief Jacobian block J (symmetric 3 x 3) of a spring of stiffness k and rest length rest
/// whose ends are d apart: f_a = -J (x_a - x_b) to first order. clamp: drop the negative part
/// of the geometric term, so that J stays positive semidefinite.
Eigen::Matrix3d spring_block(const Eigen::Vector3d& d, double k, double rest, bool clamp);

class Membrane {
 public:
  /// @brief Membrane springs for every pair of parallel structure or shear springs (a top
  /// spring a-b with its bottom twin a'-b', vertices 2c (bottom) and 2c + 1 (top) of couple c).
  /// Pairs of flex springs are carried too, without a membrane spring of their own.
  Membrane(const std::vector<int>& sa, const std::vector<int>& sb, const std::vector<std::uint8_t>& kind);

  /// @brief Top-bottom diagonals (a-b', a'-b) that the springs sa, sb lack: the caller appends
  /// them as kPatternSpring springs, then calls link().
  std::vector<std::pair<int, int>> missing_diagonals(const std::vector<int>& sa, const std::vector<int>& sb) const;
  /// @brief Resolve each membrane spring's six two-vertex blocks to springs of sa, sb (which now
  /// hold every diagonal) and set the rest lengths from the rest positions.
  void link(const std::vector<int>& sa, const std::vector<int>& sb, const RowMatX3& rest, int couples);

  int size() const { return static_cast<int>(ca_.size()); }
  int couple_a(int e) const { return ca_[e]; }
  int couple_b(int e) const { return cb_[e]; }
  /// @brief The layer springs (top, bottom) whose membrane part e carries.
  int top(int e) const { return top_[e]; }
  int bottom(int e) const { return bot_[e]; }
  /// @brief Per spring: whether it is one of a pair of layer springs that keeps only its
  /// bending part (its membrane part on a membrane spring).
  bool carried(int s) const { return s < static_cast<int>(carried_.size()) && carried_[s]; }

  /// @brief Stiffness per membrane spring, N/m (the caller's spring constants and strength).
  std::vector<double>& stiffness() { return k_; }
  /// @brief Rest lengths (between couples' centres); base: those of the rest lattice.
  std::vector<double>& rest() { return rest_; }
  const std::vector<double>& rest() const { return rest_; }
  const std::vector<double>& base() const { return base_; }

  /// @brief The yarns' stiffness: stretched beyond (1 + knee) L0 (L0 the rest lattice's length,
  /// base()), membrane spring e stiffens by knee_stiffness()[e] N/m, as a woven fabric does
  /// once its yarns are straight (docs/dynamics.md §3.4, "The knee"). knee <= 0: none.
  void set_knee(double knee) { knee_ = knee; }
  /// @brief Per membrane spring, N/m (the caller's k_limit and strength; 0: none).
  std::vector<double>& knee_stiffness() { return k_knee_; }
  /// @brief The knee at the corners of an M x M grid lattice (couple i M + j; none for M < 2):
  /// the sheet's diagonal there, g = c_b + c_c - 2 c_a (corner couple a, its neighbours b and
  /// c), stiffens as a membrane spring does beyond (1 + knee) of its rest length, by the mean
  /// knee stiffness of the pairs a-b and a-c. Near a lattice corner the mesh is the corner
  /// cell's bilinear map, whose tangent along the diagonal is g: with the cell's sides long
  /// and its cross diagonal short, each within the strain limit, g was 7.9 % long at a pinned
  /// corner and the mesh's diagonal edges there 6.6 % (docs/dynamics.md §3.4, "Corners").
  /// Call after link().
  void add_corners(int M);
  int corners() const { return static_cast<int>(corner_.size()); }

  /// @brief Force on control vertex v (half its couple's centre force), N.
  Eigen::Vector3d force(int v, const RowMatX3& x) const;
  /// @brief Elastic energy, J.
  double energy(const RowMatX3& x) const;
  /// @brief Largest |l / L - 1| over membrane springs of which a couple is flagged (per vertex).
  double max_strain(const RowMatX3& x, const std::vector<int>& slot) const;
  /// @brief Jacobian blocks of the membrane springs touching a vertex with slot >= 0 (all when
  /// slot is empty); clamp: positive semidefinite, as the solver's springs.
  void blocks(const RowMatX3& x, const std::vector<int>& slot, bool clamp);
  /// @brief What the membrane adds to spring s's 3 x 3 block (symmetric, after blocks()).
  Eigen::Matrix3d share(int s) const;
  /// @brief Gershgorin row bound of vertex v (for the explicit integrators' frequency bound).
  double row_bound(int v, const RowMatX3& x, const Eigen::VectorXd& mass) const;

 private:
  /// Length of e beyond its knee (0 within it), and the knee's end it passed.
  double beyond_knee(int e, double l, double* end = nullptr) const;

  struct Corner {
    int a, b, c;          // corner couple, its two grid neighbours
    int ab, ac, bc;       // the membrane springs between them
    double base;          // |g| on the rest lattice
  };
  /// The corner's diagonal g, its stiffness beyond the knee (N/m) and its length beyond the
  /// knee's end (0 within it; end: that end).
  Eigen::Vector3d corner_diagonal(const Corner& k, const RowMatX3& x) const;
  double corner_k(const Corner& k) const { return 0.5 * (k_knee_[k.ab] + k_knee_[k.ac]); }
  double corner_beyond(const Corner& k, double l, double* end = nullptr) const;
  /// Its centre-level coefficients: g = sum coef_i c_i over (a, b, c).
  static constexpr double kCornerCoef[3] = {-2.0, 1.0, 1.0};

  std::vector<int> ca_, cb_, top_, bot_;
  std::vector<std::uint8_t> carried_;
  std::vector<double> k_, rest_, base_;
  double knee_ = 0.0;
  std::vector<double> k_knee_;
  std::vector<int> blk_;              // 6 per membrane spring: a-b, a'-b', a-b', a'-b, a-a', b-b'
  std::vector<int> share_start_, share_elem_;  // per spring: the membrane springs writing to it
  std::vector<double> share_w_;
  std::vector<int> couple_start_, couple_elem_;  // per couple: its membrane springs
  std::vector<Eigen::Matrix3d> jac_;  // per membrane spring: its block (blocks())
  std::vector<Corner> corner_;
};

}  // namespace thinburn
