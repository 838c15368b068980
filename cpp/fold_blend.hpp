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

#include <memory>
#include <vector>

#include "colliders.hpp"
#include "lattice.hpp"

namespace thinburn {

class FoldBlend {
 public:
  /// @brief trilinear: the mesh's points embedded trilinearly in the same M x M grid lattice.
  explicit FoldBlend(Embedding trilinear);
  /// @brief Moves the points of out (the spline's mesh) towards the trilinear map where the
  /// lattice folds now, keeping z >= z_min.
  void apply(const FfdLattice& lattice, double z_min, Eigen::Ref<RowMatX3> out);

  /// @brief Collision objects whose contact samples ride the spline (null: none). Near them
  /// the mesh keeps the spline's points: a mesh that followed the couples at a fold a collider
  /// holds hung in the air over it (a cloth on a 1 cm rod: 22.9 mm above its top against
  /// 9.4 mm). A mesh point whose spline position is within margin + kKeepNear couple spacings
  /// of a collider's surface keeps it; the blend fades in over as much again (smoothstep).
  /// Beyond, the folds of a sheet hanging from the collider keep their length: a 50 cm cloth
  /// on a 10 cm ball, with the spline alone, had its mesh edges 46 % short (p99), 3.6 % now
  /// (docs/lattice.md).
  void set_keep_out(std::shared_ptr<const Colliders> colliders, double margin);
  const std::shared_ptr<const Colliders>& keep_out() const { return keep_out_; }
  double keep_out_margin() const { return keep_out_margin_; }

  /// Fold angles (degrees) between neighbouring couple-to-couple segments: the blend starts at
  /// kFrom (the demo scenes' lattices stay below it: silk held over its table bends 19.1 at
  /// most, the others 16 at most; scripts/lattice_turns.py) and is whole at kTo (the spline
  /// there is 4 % short).
  static constexpr double kFrom = 20.0, kTo = 40.0;
  /// Share of a couple spacing beyond a collider's margin within which a mesh point keeps the
  /// spline's position (the blend is whole from twice that on). Measured on the 50 cm cloth on
  /// a 10 cm ball (p99 of its edges, worst edge): 0.25: 11.6 %, -22 %; 0.125: 6.3 %, -12.9 %;
  /// 0.0625: 3.6 %, +10.4 % (the band between the spline and the couples narrows and its edges
  /// stretch). A cloth on a 1 cm rod hangs 8.96 mm above it with any of them.
  static constexpr double kKeepNear = 0.0625;

 private:
  void couple_weights(const FfdLattice& lattice);  // fills fold_, weight_ and any_

  Embedding tri_;
  std::vector<double> fold_;    // per couple: the blend by its own fold angle
  std::vector<double> weight_;  // per couple: the largest fold_ of it and its 8 neighbours
  bool any_ = false;
  std::shared_ptr<const Colliders> keep_out_;
  double keep_out_margin_ = 0.0;
};

}  // namespace thinburn
