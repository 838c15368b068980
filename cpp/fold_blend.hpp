#pragma once
/// @brief Where a grid lattice folds, the mesh follows its couples (docs/lattice.md, "Embedding
/// and deformation": "Where the lattice folds, the mesh follows the couples").
///
/// A flat sheet's mesh rides the lattice's quadratic B-spline, which is C1 across control cells
/// (no facets) but approximates its control points: it cuts the corner of a fold between
/// couples, and the mesh across the fold shrinks (by 1 % of the fold's two half-cells at 20
/// degrees, 5 % at 45, half at a full fold; an accordion of folds leaves almost nothing). The
/// trilinear map interpolates the couples' centres, so the mesh keeps the couples' distances,
/// but it kinks at every couple line. So where the lattice folds, the mesh is blended from the
/// spline's point towards the trilinear one, by a weight that rises from 0 to 1 as the angle
/// between neighbouring couple-to-couple segments rises from kFrom to kTo, spread one couple
/// either side (so the cells on both sides of a fold are trilinear) and interpolated
/// bilinearly between couples (the blend is continuous). A lattice folded nowhere beyond kFrom
/// leaves the mesh bit for bit as the spline made it.
#include <Eigen/Core>

#include <vector>

#include "lattice.hpp"

namespace thinburn {

class FoldBlend {
 public:
  /// @brief trilinear: the mesh's points embedded trilinearly in the same M x M grid lattice.
  explicit FoldBlend(Embedding trilinear);
  /// @brief Moves the points of out (the spline's mesh) towards the trilinear map where the
  /// lattice folds now, keeping z >= z_min.
  void apply(const FfdLattice& lattice, double z_min, Eigen::Ref<RowMatX3> out);

  /// Fold angles (degrees) between neighbouring couple-to-couple segments: the blend starts at
  /// kFrom (the demo scenes' lattices stay below it: silk held over its table bends 19.1 at
  /// most, the others 16 at most; scripts/lattice_turns.py) and is whole at kTo (the spline
  /// there is 4 % short).
  static constexpr double kFrom = 20.0, kTo = 40.0;

 private:
  void couple_weights(const FfdLattice& lattice);  // fills fold_, weight_ and any_

  Embedding tri_;
  std::vector<double> fold_;    // per couple: the blend by its own fold angle
  std::vector<double> weight_;  // per couple: the largest fold_ of it and its 8 neighbours
  bool any_ = false;
};

}  // namespace thinburn
