#pragma once
/// @brief Bending (paper §4.2-4.3, eqs 2-6): heat from fire particles and pyrolysis from
/// ignition points differ between a couple's top and bottom control vertices, and that
/// difference is the rotation D that bends the lattice.
#include "heat.hpp"

#include <Eigen/Core>

#include "param_table.hpp"

namespace thinburn {

/// @brief Coefficients of eqs 2-6 (SI units; see docs/bending.md for their scale).
struct BendingParams {
  double ct = 1e-7;        ///< eq 2 heat coefficient: heat units per (K · s / m²)
  double cp = 1.0;         ///< eq 3 pyrolysis coefficient (Table 1 Cp), per metre⁻¹
  double alpha = 1.0;      ///< eq 6 radians per unit heat difference
  double beta = 1e-3;      ///< eq 6 radians per unit pyrolysis difference
  double d_min = 0.005;    ///< m, guards d → 0 in eqs 2 and 3
  /// m: eq 3 counts the ignition points within this distance (0: all, the paper's reading).
  /// 3 cm holds the burning band of every preset (V0 x burn time: 12-24 mm); with all points,
  /// a burning corner's curl lifted an A4 sheet's far corner 34 mm (docs/dynamics.md §2,
  /// "Pyrolysis reaches as far as").
  double pyrolysis_range = 0.03;
  /// rad: |D| saturates smoothly here (D = Dmax tanh(D_raw / Dmax)), so the curl rolls across
  /// the front at most this far between neighbouring couples: a lattice bent by theta carries
  /// the mesh on chords, its edges shorter by about theta^2 / 24 (6 % at the old 1.2 rad).
  /// Measured unburnt-edge strain p99 at 40 s, 96 cells, 1.2 rad -> 0.4 rad: A4 on a table
  /// 4.8 % -> 0.5 %, a lantern 2.7 % -> 1.6 %, a sphere 3.7 % -> 0.5 % (docs/dynamics.md, "Bend limit").
  double max_rotation = 0.4;
  double tolerance = 0.01; ///< relative error bound of the fast kernel sums
  bool fast = true;        ///< octree sums (false: the direct all-pairs reference)

  /// @brief The table of these fields (param_table.hpp): names, bounds, docs.
  static const std::vector<param::Field<BendingParams>>& fields();
};

/// @brief Throw std::invalid_argument naming the first invalid field and its bound.
void validate(const BendingParams& p);

class Bending {
 public:
  /// @param couples M*M; the lattice has 2*M*M control vertices, index 2*couple + k (k=1 top).
  Bending(int couples, const BendingParams& p);

  /// @brief Eq 2: add the heat that the particles (positions, temperatures) give the control
  /// vertices over dt. Heat accumulates over steps; heat_rate() is this step's heat / dt.
  void add_particle_heat(const RowMatX3& control, const RowMatX3& particles,
                         const Eigen::VectorXd& temperature, double dt);
  /// @brief Eq 3: pyrolysis at the control vertices from the ignition points (recomputed).
  void set_pyrolysis(const RowMatX3& control, const RowMatX3& ignition_points);
  /// @brief Eqs 4-6: D = alpha (T_top - T_bottom) + beta (P_top - P_bottom) per couple,
  /// saturated at max_rotation: heat keeps accumulating (eq 2) but a charred area cannot
  /// fold over more than about 70 degrees about its couple.
  void rotation(Eigen::VectorXd& out) const;

  const Eigen::VectorXd& heat() const { return heat_; }
  const Eigen::VectorXd& heat_rate() const { return rate_; }
  const Eigen::VectorXd& pyrolysis() const { return pyro_; }
  const BendingParams& params() const { return p_; }

 private:
  KernelSumOptions options(int power) const;

  BendingParams p_;
  int couples_;
  Eigen::VectorXd heat_, rate_, pyro_, step_heat_;
};

}  // namespace thinburn
