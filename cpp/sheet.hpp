#pragma once
/// @brief The sheet: an input triangle mesh, its rest parameterisation, and the N×N cells
/// laid over it (paper §3.1).
///
/// The rest parameterisation is the mesh's UV scaled to metres when UV is given, else the
/// projection onto the mesh's best-fit plane. Cells cover the bounding rectangle of the
/// parameterisation; a cell is "inside" (part of the sheet) when its centre lies on a
/// triangle or a vertex falls in it, so holes and non-rectangular outlines never burn.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace thinburn {

using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using RowMatX2 = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
using RowMatX3i = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief The rest plane: origin, in-plane axes u (columns) and v (rows), normal n.
struct SheetFrame {
  Eigen::Vector3d origin, u, v, n;
};

class Sheet {
 public:
  /// @brief Build the sheet. uv may be empty (0 rows) for a planar projection.
  /// @param cells N, the number of cells along each side of the parameter rectangle.
  Sheet(const RowMatX3& vertices, const RowMatX3i& faces, const RowMatX2& uv, int cells);

  int cells() const { return n_; }
  int num_cells() const { return n_ * n_; }
  double du() const { return du_; }  ///< cell width along u (columns), m
  double dv() const { return dv_; }  ///< cell height along v (rows), m
  double size_u() const { return du_ * n_; }
  double size_v() const { return dv_ * n_; }
  double area() const { return area_; }  ///< 3-D area of the mesh, m^2
  const SheetFrame& frame() const { return frame_; }

  const std::vector<std::uint8_t>& inside() const { return inside_; }
  /// @brief Rest positions of all cell centres, (N*N)x3; cells outside the outline carry the
  /// position of the nearest inside cell's surface, extrapolated, so the lattice can be draped.
  const RowMatX3& cell_rest() const { return cell_rest_; }
  /// @brief Unit rest normals per cell (consistent orientation, from the parameter grid).
  const RowMatX3& cell_rest_normal() const { return cell_normal_; }
  /// @brief Parameter coordinates (u, v) in metres of the vertices, from the rectangle's corner.
  const RowMatX2& vertex_param() const { return vertex_param_; }
  const RowMatX3& vertices() const { return vertices_; }

  /// @brief Bilinear interpolation of a per-cell field at every vertex, using inside cells only
  /// (weights renormalised over them). out has one entry per vertex.
  void cells_to_vertices(const double* cell_values, double* out) const;
  /// @brief The inside cell nearest to each vertex (for per-vertex event times).
  const std::vector<int>& vertex_cell() const { return vertex_cell_; }
  /// @brief Per cell: itself when inside, else the nearest inside cell (4-connected distance).
  const std::vector<int>& nearest_inside() const { return nearest_inside_; }

  /// @brief Lattice parameters (s along rows, t along columns, in [0, M-1]) of a point
  /// with parameter coordinates (u, v).
  Eigen::Vector2d lattice_st(double u, double v, int M) const;

 private:
  void build_parameterisation(const RowMatX2& uv, const RowMatX3i& faces);
  void rasterise(const RowMatX3i& faces);
  void fill_outside();
  void build_normals();
  void build_vertex_weights();

  int n_;
  double du_ = 1, dv_ = 1, area_ = 0;
  SheetFrame frame_;
  RowMatX3 vertices_;
  RowMatX2 vertex_param_;
  std::vector<std::uint8_t> inside_;
  RowMatX3 cell_rest_, cell_normal_;
  std::vector<int> vertex_cell_;
  std::vector<int> nearest_inside_;  // per cell: itself when inside, else the nearest inside cell
  std::vector<int> vw_cell_;      // 4 cells per vertex
  std::vector<double> vw_weight_; // 4 weights per vertex, summing to 1 over inside cells
};

}  // namespace thinburn
