#pragma once
/// @brief Strain limiting of the lattice's mid-surface (docs/dynamics.md §3.4).
///
/// Table 1's spring constants are the paper's, and on the lattice a sheet's membrane stiffness
/// is a few N/m: a 40 cm square of silk (0.65 kg/m², K_structure 0.01) held at its corners
/// stretches by 7-10 % near its pins under its own weight, where real silk stretches by a
/// fraction of that. Stiffer springs would stiffen the implicit system by the same factor (and
/// the conjugate gradients' iterations by its square root). Instead, after each substep, the
/// distance between the centres of two neighbouring couples (structure and shear neighbours) is
/// kept within (1 +- limit) of its rest length, by moving the two couples along the line that
/// joins their centres in inverse proportion to their masses, and taking away their relative
/// speed along that line where it would take them further (after Provot 1995, "Deformation
/// constraints in a mass-spring model to describe rigid cloth behavior"). A couple moves as a whole, so its thickness and its
/// bending are left as they are: the limit keeps the layer from stretching or squashing, not
/// from curling.
///
/// The mesh lies in the mid-surface, and a quadratic B-spline's tangent is a convex
/// combination of its control points' differences along each axis: bounding those bounds the
/// mesh's stretch to first order.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "lattice.hpp"

namespace thinburn {

class StrainLimit {
 public:
  /// @brief The couple pairs of topology's top-layer structure and shear springs, with their
  /// centres' rest distances in rest ((2 couples) x 3).
  StrainLimit(const LatticeTopology& topology, const RowMatX3& rest);

  int size() const { return static_cast<int>(ca_.size()); }
  int couple_a(int e) const { return ca_[e]; }
  int couple_b(int e) const { return cb_[e]; }
  double rest(int e) const { return rest_[e]; }

  /// @brief Keep |l / L - 1| <= limit (> 0) for every pair of which at least one couple moves
  /// (both its vertices have slot >= 0), burnt or not: freeing charring pairs let the unburnt
  /// sheet beside them stretch 5.5-7.2 % (docs/dynamics.md §3.4). Gauss-Seidel sweeps in a
  /// fixed order (deterministic), at most kSweeps; a pair beyond the limit is put kInside of it
  /// inside, and loses the part of its centres' relative speed that takes it further out.
  /// At each corner of a grid lattice the sheet's diagonal there, x_b + x_c - 2 x_a for the
  /// corner couple a and its two neighbours b and c, is kept within the same bound of its
  /// rest length: near a lattice corner the mesh is the corner cell's bilinear map, whose
  /// tangent along the diagonal is that vector, and with the cell's sides long and its cross
  /// diagonal short (each within the limit) it was 7.9 % long at a pinned corner, and the mesh's
  /// diagonal edges there 6.6 % (docs/dynamics.md §3.4, "Corners").
  /// Returns the pairs (and corners) corrected in the first sweep.
  int apply(double limit, RowMatX3& x, RowMatX3& v, const Eigen::VectorXd& mass,
            const std::vector<int>& slot);

  /// Most sweeps per call. A call stops at the first sweep that finds nothing beyond the limit;
  /// a substep moves the sheet little, so most stop after one.
  static constexpr int kSweeps = 64;
  /// A pair beyond the limit is put back this share of the limit inside it.
  static constexpr double kInside = 0.1;

 private:
  std::vector<int> ca_, cb_;    // couples
  std::vector<double> rest_;    // rest distance between their centres
  std::vector<int> candidates_; // scratch: pairs that may be corrected this call
  struct Corner {
    int a, b, c;    // the corner couple and its two neighbours along the grid
    double rest;    // |x_b + x_c - 2 x_a| at rest (centres)
  };
  std::vector<Corner> corner_;
  int limit_corner(const Corner& k, double limit, RowMatX3& x, RowMatX3& v, const Eigen::VectorXd& mass,
                   const std::vector<int>& slot) const;
};

}  // namespace thinburn
