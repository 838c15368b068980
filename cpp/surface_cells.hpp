#pragma once
/// @brief Cells on a triangulated surface: a uniform sampling of the surface itself, for the
/// fire front on shells (MODEL.md §9; docs/surface_front.md).
///
/// The input mesh is welded by position, checked (manifold edges, non-zero area), oriented
/// per piece, and refined until every edge is shorter than spacing / refine ("dense mesh").
/// Cells are farthest-point samples of the dense mesh's vertices (graph-geodesic distance),
/// relaxed by a few Lloyd steps; each cell owns its Voronoi region of dense vertices. The
/// cells' triangulation is the dual of that partition (a dense triangle whose three vertices
/// lie in three different regions gives a cell triangle). The result depends on the surface,
/// not on how densely or how it was triangulated, nor on how it lies in space.
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace thinburn {

struct Creases;

using SurfVerts = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using SurfFaces = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief Resolution and construction settings of SurfaceCells.
struct CellOptions {
  /// About cells^2 cells over the total area (as the sheet's N x N grid) unless spacing > 0.
  int cells = 64;
  /// Explicit target spacing between neighbouring cells (m); > 0 overrides `cells`.
  double spacing = 0.0;
  /// Vertices closer than weld_tol * (bounding-box diagonal) are one vertex (UV seams).
  double weld_tol = 1e-6;
  /// Lloyd relaxation steps after farthest-point sampling (evens out the cells' shapes).
  int lloyd_iters = 3;
  /// The dense mesh's edges are at most spacing / refine.
  double refine = 3.0;
  /// Seed the mesh's boundary first, about a spacing apart along it, and keep those cells'
  /// positions on it while relaxing (a lattice's rim couples; the fire's cells do not).
  bool rim_seeds = false;
  /// > 0: edges where the surface turns by more than this (rad) are creases (cpp/creases.hpp):
  /// they are seeded first as the rim is, and each cell knows the sides of the creases it lies
  /// on (a lattice's couples; docs/lattice.md, "Creases"). 0: no creases.
  double crease_angle = 0.0;
};

/// @brief Nearest-point queries on a fixed 3-D point set: a k-d tree, O(log n) per query.
class KdTree3 {
 public:
  KdTree3() = default;
  explicit KdTree3(const std::vector<Eigen::Vector3d>& points);
  /// @brief Index of the point nearest to q (-1 if the set is empty).
  int nearest(const Eigen::Vector3d& q) const;

 private:
  void build(int lo, int hi);
  void search(int lo, int hi, const Eigen::Vector3d& q, int* best, double* best_d2) const;
  std::vector<Eigen::Vector3d> pts_;
  std::vector<int> idx_;
  std::vector<signed char> axis_;
};

/// @brief The cells of a surface: positions, normals, areas, neighbour graph, triangulation.
class SurfaceCells {
 public:
  /// @brief Build the cells of the mesh (vertices n x 3, faces m x 3 vertex indices).
  /// Throws std::invalid_argument naming `vertices` or `faces` for non-finite vertices,
  /// indices out of range, a face repeating a vertex, an edge shared by more than two faces
  /// (non-manifold), or zero total area. Faces that are degenerate after welding (zero
  /// area) are dropped; vertices on no face are mapped to their nearest cell.
  SurfaceCells(const SurfVerts& vertices, const SurfFaces& faces,
               const CellOptions& options = CellOptions());

  int size() const { return static_cast<int>(pos_.size()); }
  /// @brief Target spacing h between neighbouring cells (m).
  double spacing() const { return h_; }
  /// @brief Total area of the surface (m^2).
  double total_area() const { return area_total_; }
  /// @brief Cell position: a point on the input surface (m).
  const std::vector<Eigen::Vector3d>& positions() const { return pos_; }
  /// @brief Unit normal (area-weighted over the cell's region; oriented per piece).
  const std::vector<Eigen::Vector3d>& normals() const { return nrm_; }
  /// @brief Area of the cell's region (m^2); they sum to total_area().
  const std::vector<double>& areas() const { return area_; }
  /// @brief Gaussian curvature of the cell's region (1/m^2): the angle deficits of the
  /// dense mesh's interior vertices in the region over its area (discrete Gauss-Bonnet).
  const std::vector<double>& gauss_curvature() const { return gauss_; }
  /// @brief 1 where the cell's region touches the mesh's boundary (an open edge or a hole).
  const std::vector<std::uint8_t>& on_boundary() const { return boundary_; }
  /// @brief Neighbours of cell c: nbr_index()[nbr_offset()[c] .. nbr_offset()[c+1]).
  const std::vector<int>& nbr_offset() const { return nbr_off_; }
  const std::vector<int>& nbr_index() const { return nbr_idx_; }
  /// @brief Cell triangles (three cell indices each), the local triangulation of the updates.
  const std::vector<std::array<int, 3>>& triangles() const { return tri_; }
  /// @brief Triangles around cell c: fan_index()[fan_offset()[c] .. fan_offset()[c+1]).
  const std::vector<int>& fan_offset() const { return fan_off_; }
  const std::vector<int>& fan_index() const { return fan_idx_; }
  /// @brief Per input vertex: three cells and weights (sum 1) interpolating cell values there.
  const std::vector<std::array<int, 3>>& vertex_cells() const { return vcell_; }
  const std::vector<std::array<double, 3>>& vertex_weights() const { return vweight_; }
  /// @brief The cell nearest (Euclidean) to a 3-D point, O(log n).
  int nearest(const Eigen::Vector3d& p) const { return tree_.nearest(p); }
  /// @brief Number of vertices of the refined (dense) mesh the cells were sampled from.
  int dense_size() const { return n_dense_; }
  /// @brief The side point p lies on: that of the nearest dense vertex off the creases (-1
  /// without creases); *normal (if given) gets that vertex's unit normal.
  int side_of(const Eigen::Vector3d& p, Eigen::Vector3d* normal = nullptr) const;
  /// @brief Whether cell c lies on side s: a cell on a crease lies on each side it touches.
  bool on_side(int c, int s) const;

 private:
  void set_sides(const std::vector<Eigen::Vector3d>& dense, const std::vector<std::array<int, 3>>& faces,
                 const Creases& creases,
                 const std::vector<int>& vertex_side, const std::vector<std::pair<int, int>>& cell_sides);

  double h_ = 0.0, area_total_ = 0.0;
  int n_dense_ = 0;
  std::vector<Eigen::Vector3d> pos_, nrm_;
  std::vector<double> area_, gauss_;
  std::vector<int> nbr_off_, nbr_idx_, fan_off_, fan_idx_;
  std::vector<std::array<int, 3>> tri_;
  std::vector<std::uint8_t> boundary_;
  std::vector<std::array<int, 3>> vcell_;
  std::vector<std::array<double, 3>> vweight_;
  KdTree3 tree_;
  int sides_ = 0;                        // the sides the creases cut the surface into (0: none)
  std::vector<int> side_off_, side_idx_;  // per cell, the sides of the faces near it
  KdTree3 side_tree_;                     // the dense vertices off the creases ...
  std::vector<int> side_vertex_;          // ... and their sides
  std::vector<Eigen::Vector3d> side_normal_;  // ... and normals
};

}  // namespace thinburn
