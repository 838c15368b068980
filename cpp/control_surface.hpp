#pragma once
/// @brief The lattice of a curved shell (paper §4.1, Fig. 3; issue #11; docs/lattice.md):
/// couples on a coarse control surface fitted to the shell, and the shell's points embedded
/// smoothly in the layer between them.
///
/// The control surface is a SurfaceCells sampling of the shell at the lattice's spacing: its
/// cells are the couples' mid-points (on the shell), their normals the couples' axes, and
/// their triangulation gives the springs: structure along its edges, flex across each interior
/// edge (the two opposite corners), thickness per couple, transverse along each edge. The
/// paper's grid lattice is the special case of a flat sheet (grid_topology, FfdLattice::embed);
/// this class serves every other shell: tubes, spheres, folds, pieces.
///
/// Creases (edges turning past 25 degrees, cpp/creases.hpp) are hinges: couples sit along them
/// and a point is embedded from the couples of its own side of them and those on them.
///
/// Embedding. A point x gets weights over the couples within R of it (4 rings of its nearest
/// couple on the control surface, so the far side of a fold or another piece never counts):
/// moving least squares, linear in 3-D (with a ridge on the normal term, which leaves the
/// tangent-plane MLS where the couples are flat), with Wendland C2 window functions. The
/// weights sum to 1, reproduce linear motion of the layer (a rigid turn too) and are C2 in x,
/// so a fine mesh shows no lattice facets. A point follows the mid-surface's displacement, plus its rest
/// offset along the layer's interpolated normal turned with the layer: a curved shell's points,
/// which lie off the couples' interpolated mid-surface by the sag of the curve, stay at that
/// offset across the layer as it bends.
#include <Eigen/Core>

#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "lattice.hpp"
#include "surface_cells.hpp"

namespace thinburn {

/// Mesh edges whose faces turn by more than this many degrees are creases (docs/lattice.md,
/// "Creases"). Blender shades edges sharper than 30 degrees flat by default; a cylinder of 8
/// sides (45 degrees) is a prism of creases, one of 15 (24 degrees) still a smooth tube.
constexpr double kDefaultCreaseAngle = 25.0;

/// @brief Points embedded in a control surface's lattice.
struct SurfaceEmbedding {
  static constexpr int kStencil = 24;  ///< couples per point (unused slots: weight 0)
  std::vector<std::int32_t> couple;    ///< n * kStencil couple indices
  std::vector<double> weight;          ///< n * kStencil MLS weights (sum 1; may be < 0)
  std::vector<double> share;           ///< n * kStencil window shares (>= 0, sum 1): mass, area, pins
  RowMatX3 rest;                       ///< n x 3 rest positions
  RowMatX3 rest_normal;                ///< n x 3 the layer's interpolated unit normal at rest
  Eigen::VectorXd offset;              ///< n: rest offset along rest_normal from the interpolated mid-surface
  Eigen::Index size() const { return rest.rows(); }
};

class ControlSurface {
 public:
  /// @brief The control surface of the mesh at `spacing` (m) between couples; the layer is
  /// `thickness` thick (m, > 0); edges turning by more than `crease_angle` degrees are creases
  /// (180: none). Throws std::invalid_argument naming `vertices`/`faces` for a
  /// mesh SurfaceCells refuses, or `lattice` when the spacing leaves fewer than 3 couples on a
  /// piece or a couple without neighbours.
  ControlSurface(const SurfVerts& vertices, const SurfFaces& faces, double spacing, double thickness,
                 double crease_angle = kDefaultCreaseAngle);

  int couples() const { return coarse_->size(); }
  double spacing() const { return coarse_->spacing(); }
  double thickness() const { return thickness_; }
  /// @brief Rest positions of the control vertices (2 couples x 3; 2 c + 1 the top of couple c).
  const RowMatX3& rest() const { return rest_; }
  const LatticeTopology& topology() const { return topo_; }
  const SurfaceCells& cells() const { return *coarse_; }

  /// @brief How strongly the shell curves at this spacing: the given quantile (0..1) over the
  /// couples of their most curved edge's turn (the angle between its ends' normals over its
  /// length, 1/m).
  double edge_curvature(double quantile) const;
  /// @brief Embed rest points lying on (or near) the shell. seeds: per point a couple of its own
  /// piece of the shell near it (its window's rings start there), or empty: the nearest couple.
  /// Sheets stacked closer than the couples' spacing need seeds, else a point may take the
  /// sheet above's couples.
  SurfaceEmbedding embed(const RowMatX3& points, const std::vector<int>& seeds = {}) const;
  /// @brief Deformed positions of all embedded points from the lattice's control positions;
  /// heights below z_min are raised to it. Parallel over points, bit-identical for any count.
  void deform(const SurfaceEmbedding& e, const RowMatX3& control, RowMatX3& out,
              double z_min = -std::numeric_limits<double>::infinity()) const;
  /// @brief Deformed position of embedded point i.
  Eigen::Vector3d point(const SurfaceEmbedding& e, Eigen::Index i, const RowMatX3& control) const;
  /// @brief The layer's unit normal (bottom -> top) at embedded point i now.
  Eigen::Vector3d normal(const SurfaceEmbedding& e, Eigen::Index i, const RowMatX3& control) const;

 private:
  void build_topology();
  void tie_loose_couples(std::map<std::pair<int, int>, std::vector<int>>& edges) const;
  void gather(int start, std::vector<int>& out, std::vector<int>& stamp, int& id) const;
  void keep_side(int side, std::vector<int>& cand) const;

  std::shared_ptr<const SurfaceCells> coarse_;
  double thickness_;
  RowMatX3 rest_;
  LatticeTopology topo_;
};

}  // namespace thinburn
