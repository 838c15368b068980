#pragma once
/// @brief The FFD lattice of Liu et al. 2009 §4.1: M x M couples of control vertices (a bottom
/// and a top vertex in charge of the same area of the sheet) and the embedding of points in it.
///
/// Control vertex index: ((i * M) + j) * 2 + k, i = row (the sheet's v axis), j = column (u
/// axis), k = 0 bottom, 1 top. A point's deformed position is its rest position plus the
/// interpolated DISPLACEMENT (current - rest) of the control vertices, so the rest mesh is
/// reproduced exactly at rest whatever shape the lattice was draped into.
#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>
#include <mutex>
#include <vector>

namespace thinburn {

using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief In-plane interpolation of the lattice (always linear through the thickness).
enum class LatticeInterp {
  Trilinear,        ///< bilinear in the sheet's plane: 2 x 2 couples per point
  QuadraticBSpline  ///< uniform quadratic B-spline in the plane: 3 x 3 couples, C1 across cells
};

/// @brief Points embedded in a lattice: per point a stencil of couples with in-plane weights,
/// the weight of the top layer and the rest position.
struct Embedding {
  int stencil = 4;                ///< couples per point: 4 (trilinear) or 9 (B-spline)
  std::vector<std::int32_t> couple;  ///< n * stencil couple indices (i * M + j)
  std::vector<double> weight;     ///< n * stencil in-plane weights, each point's sum to 1
  Eigen::VectorXd r;              ///< n: weight of the top vertex of each couple (1 - r: bottom)
  RowMatX3 rest;                  ///< n x 3: rest positions of the points
  /// @brief Number of embedded points.
  Eigen::Index size() const { return r.size(); }
};

class FfdLattice;

/// @brief The deformed positions of one embedding, kept from call to call. A call redoes only
/// the points one of whose couples moved, with FfdLattice::deform's kernel on the same
/// displacement table. A couple has moved when an entry of its table rows differs from the
/// value kept for it at its last redo by more than the tolerance (tolerance 0: bitwise, so a
/// sleeping couple keeps its points as they were and the positions are bit-identical to a full
/// deform). Kept per couple, not the last call's table: a slow creep adds up until it counts.
/// With a tolerance every point is within 2 x tolerance (each coordinate) of the full deform
/// (the proof is at moved_points, lattice.cpp). The points are grouped by stencil (all the
/// points of a control cell read the same couples), so a moving region redoes its own points
/// only. When more than half of them moved, a call deforms every point straight into the
/// caller's rows, as FfdLattice::deform (no copy), and the next call with fewer moved deforms
/// every point once more to keep them. One call at a time (a mutex).
class CachedDeform {
 public:
  CachedDeform() = default;
  /// @brief For points embedded in a lattice of `couples` couples (the embedding is not kept:
  /// each call takes it again, and it must be the same one). tolerance: m a couple's
  /// displacement may drift from its last redo before its points are redone (>= 0, finite).
  CachedDeform(const Embedding& e, int couples, double tolerance = 0.0);
  /// @brief The points deformed by the lattice's control positions now, into out (n x 3);
  /// z_min as FfdLattice::deform (a change redoes every point).
  void deform_into(const FfdLattice& lattice, const Embedding& e, double z_min, Eigen::Ref<RowMatX3> out);
  /// @brief Points the last call computed (the others were copied from the call before).
  long points_redone() const { return redone_; }
  /// @brief Groups of points that share a stencil.
  long groups() const { return static_cast<long>(group_offset_.size()) - 1; }
  /// @brief m, the drift of a couple's displacement that redoes its points.
  double tolerance() const { return tolerance_; }

 private:
  long moved_points(const std::vector<double>& table, double z_min);  // fills moved_, dirty_
  bool couple_moved(const double* now, const double* kept) const;
  void keep_moved_couples(const std::vector<double>& table);
  void deform_all(const Embedding& e, const double* table, int couples, double z_min, Eigen::Ref<RowMatX3> out);
  Eigen::Index points_ = 0;
  int stencil_ = 0;
  double tolerance_ = 0.0;
  std::vector<int> group_offset_;            // group g: group_points_[group_offset_[g] .. [g + 1])
  std::vector<std::int32_t> group_points_;   // point indices, grouped
  std::vector<int> group_couples_;           // per group its stencil's couples
  std::vector<double> kept_;                 // per couple, its displacement-table rows at its last redo
  std::vector<std::uint8_t> moved_;          // per couple, scratch
  std::vector<long> dirty_;                  // groups to redo, scratch
  RowMatX3 positions_;                       // the points as of kept_ (when positions_valid_)
  double z_min_ = 0.0;
  bool kept_valid_ = false, positions_valid_ = false;
  long redone_ = 0;
  std::mutex mutex_;
};

/// @brief Which control vertices are joined by springs, and which couples are neighbours.
///
/// Spring kinds: 0 structure (neighbouring couples, per layer), 1 shear (a grid cell's
/// diagonals, per layer), 2 flex (couples two apart, per layer), 3 thickness (a couple's own
/// bottom-top), 4 transverse (bottom of one couple to the top of a neighbour, and back).
struct LatticeTopology {
  int couples = 0;
  int grid_side = 0;                  ///< M for an M x M grid lattice, 0 on a control surface
  std::vector<int> spring_a, spring_b;  ///< control vertex indices (2 couple + layer)
  std::vector<std::uint8_t> kind;
  /// Neighbours of couple c: nbr_index[nbr_offset[c] .. nbr_offset[c+1]) (the structure springs').
  std::vector<int> nbr_offset, nbr_index;
  int springs() const { return static_cast<int>(kind.size()); }
};

/// @brief Per control vertex, the springs that touch it (CSR, in spring order): vertex v's are
/// spring[q] for q in [start[v], start[v + 1]), other[q] the spring's far end.
struct SpringIncidence {
  std::vector<int> start, spring, other;
};

/// @brief Centre of couple c (the mean of its two vertices' rows in x).
inline Eigen::Vector3d couple_centre(const RowMatX3& x, int c) {
  return 0.5 * (x.row(2 * c) + x.row(2 * c + 1)).transpose();
}

/// @brief Per couple, the rest shell's shape operator S (3 x 3, acting in the couple's tangent
/// plane, zero along its axis): how the couples' axes (bottom -> top, the shell's normals) turn
/// towards its neighbours, dn = S de in the tangent plane, fitted by least squares over the
/// neighbours with S symmetric. A sphere of radius R whose tops face out gives I/R in its
/// tangent plane; a flat lattice, or a couple whose neighbours do not span two directions, zero.
std::vector<Eigen::Matrix3d> shape_operators(const RowMatX3& rest, const LatticeTopology& topo);

/// Work of one item of a loop over the lattice, in kParallelWork's units (threads.hpp): a
/// vertex's or a spring's row of forces, Jacobian or CG product is about 32. So a loop over
/// fewer than about 1000 vertices stays on one thread.
constexpr long kRowCost = 32;

/// @brief The paper's M x M lattice (§4.1, Fig. 3): structure, shear and flex springs per layer,
/// then per couple its thickness spring and the transverse pairs to its +j and +i neighbours;
/// neighbours in the order (i-1, j), (i+1, j), (i, j-1), (i, j+1).
LatticeTopology grid_topology(int M);

/// @brief The four corners of an M x M grid lattice (none for M < 2), couple i M + j: each as
/// (the corner couple, its neighbour along i, its neighbour along j).
std::vector<std::array<int, 3>> grid_corners(int M);

/// @brief An M x M lattice of couples: rest and current positions of its 2 M^2 control vertices.
class FfdLattice {
 public:
  /// @brief rest: (2 M^2) x 3 rest positions of the control vertices (M >= 2, finite).
  FfdLattice(int M, const RowMatX3& rest);
  /// @brief A lattice whose couples follow a shell's control surface (not a grid): rest has
  /// 2 * couples rows, vertex 2 c + k of couple c (k = 1 top). M() is 0 and embed() refuses;
  /// points are embedded by the control surface (control_surface.hpp).
  static FfdLattice on_surface(int couples, const RowMatX3& rest);

  /// @brief Embed points. params: n x 3 lattice coordinates (s in [0, M-1] along rows i, t in
  /// [0, M-1] along columns j, r in [0, 1] bottom -> top); rest_points: their rest positions.
  Embedding embed(const RowMatX3& params, const RowMatX3& rest_points,
                  LatticeInterp interp = LatticeInterp::Trilinear) const;

  /// @brief One point's in-plane stencil at lattice coordinates (s, t) (clamped to the
  /// lattice): couples (i * M + j) and weights, 4 (trilinear) or 9 (B-spline); returns the count.
  /// The weights embed() gives that point.
  int plane_stencil(double s, double t, LatticeInterp interp, int* couple, double* w) const;

  /// @brief Deformed positions of embedded points (n x 3, preallocated) from the current
  /// control positions. Each control vertex's displacement is computed once per call into a
  /// table owned by the calling thread (allocated on its first call, reused after); then
  /// parallel over points, bit-identical for any thread count. z_min: heights below it are
  /// raised to it in the same pass (a floor; the default leaves every point as it is). Throws
  /// std::invalid_argument when out has the wrong size or the embedding does not fit the
  /// lattice (out is then partly written).
  void deform(const Embedding& e, Eigen::Ref<RowMatX3> out,
              double z_min = -std::numeric_limits<double>::infinity()) const;

  /// @brief The per-couple displacement table deform reads: 8 doubles per couple, bottom
  /// (x, y, z, 0) then top (x, y, z, 0), current minus rest.
  void displacement_table(std::vector<double>& table) const;

  /// @brief Spread per-point values onto the control vertices with the embedding's weights
  /// (the transpose of the interpolation): sum over points of weight * value. Serial, fixed order.
  Eigen::VectorXd scatter(const Embedding& e, const Eigen::VectorXd& values) const;

  /// @brief Current control positions ((2 M^2) x 3), writable.
  RowMatX3& positions() { return pos_; }
  /// @brief Current control positions ((2 M^2) x 3).
  const RowMatX3& positions() const { return pos_; }
  /// @brief Rest control positions ((2 M^2) x 3).
  const RowMatX3& rest() const { return rest_; }
  /// @brief Couples per side of a grid lattice; 0 for a lattice on a shell's control surface.
  int M() const { return M_; }
  /// @brief Number of couples (M^2 on a grid).
  int couples() const { return couples_; }
  /// @brief Number of control vertices, 2 couples.
  int size() const { return 2 * couples_; }
  /// @brief Index of control vertex (i, j, k).
  int index(int i, int j, int k) const { return ((i * M_) + j) * 2 + k; }

 private:
  FfdLattice(const RowMatX3& rest, int M, int couples);
  int M_, couples_;
  RowMatX3 rest_, pos_;
};

}  // namespace thinburn
