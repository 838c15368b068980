#pragma once
/// @brief The bimetal curl (docs/dynamics.md §2, `bimetal`): D shrinks the heated face's
/// springs, so the springs' rest lengths are those of the rest lattice bent to a curvature of
/// crumple_gain D / spacing, across the fire's front. Rest lengths are a function of D alone,
/// not of its path: the springs never carry the history of earlier crumples.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "lattice.hpp"
#include "membrane.hpp"

namespace thinburn {

struct DynamicsParams;

class Bimetal {
 public:
  /// @brief The lattice the curl bends, kept by reference (the dynamics owns it).
  struct View {
    const LatticeTopology& topology;
    const RowMatX3& rest;              // rest positions of the control vertices
    const std::vector<int>& sa;        // per spring: its ends
    const std::vector<int>& sb;
    std::vector<double>& rest_len;     // per spring: the rest lengths the curl sets, m
    const DynamicsParams& p;
  };
  explicit Bimetal(const View& view);
  /// @brief Measure the rest lattice: its couples' spacing, and its springs as add_springs does
  /// (once, when the springs exist).
  void build();

  /// @brief Record the rest lengths and geometry of the springs added since the last call (their
  /// current rest lengths are the rest lattice's).
  void add_springs();
  /// @brief Set the rest lengths of the springs near a couple whose D changed (delta != 0), or of
  /// all of them; and the membrane springs' (null: none), a chord of the same arc.
  void apply(const Eigen::VectorXd& D, const Eigen::VectorXd& delta, bool all, Membrane* membrane);

  /// @brief Per couple: the unit direction in which D grows (rest frame) and how much of the curl
  /// follows it (0: isotropic); a step that throws puts them back.
  const RowMatX3& grad_dir() const { return grad_dir_; }
  const Eigen::VectorXd& grad_share() const { return grad_share_; }
  void restore(RowMatX3&& grad_dir, Eigen::VectorXd&& grad_share);

 private:
  double ratio(int s, double kappa) const;
  void measure_shape();
  double factor(int c, const Eigen::Vector3d& u) const;
  void update_gradients(const Eigen::VectorXd& D, const Eigen::VectorXd& delta, bool all);
  double curvature(const Eigen::VectorXd& D, int ca, int cb) const;

  View s_;
  std::vector<double> base_len_;      // rest lengths of the rest lattice (the curl scales them)
  std::vector<double> mid_sep_;       // per spring: rest distance between its couples' centres
  std::vector<double> off_a_, off_b_; // per spring: its ends' offsets from the mid-surface (+ top)
  Eigen::VectorXd couple_spacing_;    // per couple: mean rest distance to its axis neighbours
  RowMatX3 grad_dir_;                 // per couple: unit direction in which D grows (rest frame)
  Eigen::VectorXd grad_share_;        // per couple: how much of the curl follows it (0: isotropic)
  // Per couple: the cofactor of the rest shell's shape operator in its tangent plane (zero on a
  // flat sheet), and its squared norm plus that of a curvature that counts as flat: the curl's
  // part along it would change the Gaussian curvature, which a shell cannot do unstretched.
  std::vector<Eigen::Matrix3d> cofactor_;
  Eigen::VectorXd cofactor_norm2_;
  std::vector<std::uint8_t> changed_; // per couple: its springs' rest lengths are recomputed this step
};

}  // namespace thinburn
