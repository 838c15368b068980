#pragma once
/// @brief Fire particles stay outside a closed shell (docs/particles.md, "Closed shells"): a
/// paper ball lit at its bottom burns on its outside, and its flames rise round it, not up
/// through it. Particles of a closed piece are born on its outside (Simulation's find_outsides);
/// this keeps them there as buoyancy carries them along it.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "particles.hpp"
#include "point_grid.hpp"

namespace thinburn {

/// @brief Per item (a cell, a couple) of a closed piece: +1 when its piece's outside lies along
/// its normal, -1 against it; 0 on an open piece (one with an item on the mesh's boundary). The
/// outside is the side for which the enclosed volume, 1/3 of the integral of (p - c).n over
/// the surface, is positive (weights: the items' areas).
std::vector<double> outside_signs(const std::vector<int>& piece, const std::vector<std::uint8_t>& on_rim,
                                  const std::vector<Eigen::Vector3d>& position,
                                  const std::vector<Eigen::Vector3d>& normal, const std::vector<double>& weight);

class OutsideKeeper {
 public:
  /// @param piece per couple, its connected piece; @param on_rim per couple, 1 where its region
  /// touches the mesh's boundary (a piece with one is open); @param rest (2 couples) x 3 rest
  /// positions (2 c + 1 the top); @param spacing the couples' spacing, m.
  OutsideKeeper(const std::vector<int>& piece, const std::vector<std::uint8_t>& on_rim, const RowMatX3& rest,
                double spacing);

  /// @brief True when some piece is closed (otherwise apply does nothing).
  bool any() const { return !closed_.empty(); }
  /// @brief Per couple: +1 when its piece's outside is its top side, -1 its bottom, 0 open.
  const std::vector<double>& outside() const { return outside_; }

  /// @brief Every live particle within a spacing of a closed piece's couple that is less than
  /// half burnt (burnt: per couple, its burnt share) and that came within `skin` of its
  /// tangent plane from outside over the step dt goes back to `skin` outside it, its inward
  /// velocity removed (it slides along the shell). x: the lattice's positions now. Returns how
  /// many were moved.
  int apply(const RowMatX3& x, const Eigen::VectorXd& burnt, double skin, double dt, ParticleSystem& particles);

 private:
  std::vector<double> outside_;
  std::vector<int> closed_;  // the couples of closed pieces
  double spacing_ = 0.0;
  RowMatX3 mid_;              // per couple, its mid-point now (rows of closed_ only)
  PointGrid grid_;
};

}  // namespace thinburn
