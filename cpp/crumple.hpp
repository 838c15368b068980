#pragma once
/// @brief The crumple of Liu et al. 2009 §4.3 (eqs 7, 8, Fig. 5) as a displacement per control
/// vertex: a couple whose rotation D grows by delta turns its axis neighbours about a line
/// through its centre by delta, each vertex along the chord AB, |AB| = 2 r sin(|delta| / 2).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace thinburn {

using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief Chord displacement of every control vertex for per-couple rotation increments.
///
/// For couple O = (i, j) with increment delta(O) != 0, the couples (i +- 1, j) turn about the
/// line through O's centre along the lattice's column (j) direction, and (i, j +- 1) about the
/// line along the row (i) direction: both axes, full delta each, so the result is symmetric
/// under both mirrors and the transpose of the lattice. A positive delta (top hotter or more
/// pyrolysed) turns the neighbours toward O's top side: the heated face becomes concave. Both
/// vertices of a neighbour couple turn by the same rotation. Contributions of several couples to
/// one vertex add. Pinned vertices (pinned[v] != 0) get zero. Parallel over vertices, each output
/// row written once in a fixed order, so the result is bit-identical for any thread count.
/// @param M couples per side; pos (2 M^2) x 3 control positions; delta M^2 increments (rad).
/// @param out (2 M^2) x 3, overwritten.
void crumple_displacements(int M, const RowMatX3& pos, const Eigen::VectorXd& delta,
                           const std::vector<std::uint8_t>& pinned, RowMatX3& out);

/// @brief The same crumple on a lattice whose couples follow a shell's control surface: couple
/// O's neighbour B (nbr_index[nbr_offset[O] ..]) turns about the line through O's centre in O's
/// tangent plane perpendicular to O -> B, by delta(O), toward O's top side. On a grid this is the
/// grid version's axis up to the tangents' difference.
void crumple_displacements(const std::vector<int>& nbr_offset, const std::vector<int>& nbr_index,
                           const RowMatX3& pos, const Eigen::VectorXd& delta,
                           const std::vector<std::uint8_t>& pinned, RowMatX3& out);

}  // namespace thinburn
