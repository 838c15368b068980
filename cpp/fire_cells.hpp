#pragma once
/// @brief The cells the fire spreads over (paper §3.1) and their front, in one of two layouts
/// (docs/surface_front.md, "Which cells"):
///
/// - GridCells: the paper's N x N grid over the sheet's rest plane (or its UV map), with the
///   grid fronts (FireFront: the paper's 8-neighbour rule, fast marching). Exact for a flat sheet.
/// - ShellCells: cells on the surface itself (SurfaceCells) with the surface front
///   (SurfaceFront): distances on the shell, whatever its shape, seams or pose.
///
/// The Simulation keeps the fire's rules (states, burn durations, mass, eq 1's speed); a layout
/// says where its cells are, who neighbours whom, and how the world-frame spread law reads on
/// its own tangent planes.
#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "fire_front.hpp"
#include "sheet.hpp"
#include "surface_front.hpp"

namespace thinburn {

/// @brief Uniform in [-1, 1) from a seed, a stream and a key: a stateless hash (splitmix64), so
/// a cell's draw depends only on these, never on the order cells are visited.
double seeded_uniform(std::uint64_t seed, std::uint64_t stream, std::uint64_t key);

/// @brief Where the cells are now: position and unit normal of a cell.
struct CellView {
  std::function<Eigen::Vector3d(int)> position;
  std::function<Eigen::Vector3d(int)> normal;
  /// The rest shape's normal at the cell (a grid's rest plane, a surface cell's own) turned with
  /// its piece of the shell as a whole: eq 1's slope is the turn away from it, so a lantern that
  /// tips over or a curtain the wind lifts is not slowed, their curls and folds are.
  std::function<Eigen::Vector3d(int)> reference_normal;
};

/// @brief Eq 1 and the drive in world terms, for a layout to read on its tangent planes.
struct SpreadLaw {
  std::function<double(int)> v;    ///< the cell's speed now, m/s (eq 1)
  Eigen::Vector3d drive{0, 0, 0};  ///< climb * up + wind_spread * wind; zero: isotropic
  double max_drive = 0.9;          ///< cap on |e| along the sheet
};

/// @brief A per-vertex field of the input mesh read at every cell's rest position: the
/// barycentric value on the nearest input triangle (among those around the nearest input
/// vertex and its neighbours), so a map painted on a 4-vertex quad covers all N x N cells and a
/// sharp painted edge stays within a cell of where it was painted. With sharp_zero, a painted 0
/// stays 0 (a firebreak) on the cells around it rather than blending (fire_cells.cpp).
std::vector<double> vertex_field_at_cells(const class FireCells& cells, const RowMatX3& vertices,
                                          const RowMatX3i& faces, const Eigen::VectorXd& values,
                                          bool sharp_zero);

class FireCells {
 public:
  virtual ~FireCells() = default;
  /// @brief A copy sharing the (immutable) geometry, with its own front state.
  virtual std::unique_ptr<FireCells> clone() const = 0;

  virtual int size() const = 0;
  /// @brief 1 where a cell is part of the sheet (every cell of a ShellCells).
  virtual const std::vector<std::uint8_t>& inside() const = 0;
  virtual Eigen::Vector3d rest(int c) const = 0;
  virtual Eigen::Vector3d rest_normal(int c) const = 0;
  /// @brief Area of a cell, m^2.
  virtual double area(int c) const = 0;
  /// @brief Front length one fringe cell stands for, m.
  virtual double spacing() const = 0;
  /// @brief Farthest a point may lie from its nearest cell for ignite to take it, besides the
  /// caller's radius and a share of the sheet's size.
  virtual double reach() const = 0;
  virtual double total_area() const = 0;
  /// @brief Smooth seeded noise in [-1, 1] over about 10 cells, plus a little per-cell grain.
  virtual double noise(int c, std::uint64_t seed, std::uint64_t stream) const = 0;
  /// @brief grad^2 of eq 1: the squared slope of the surface now out of its rest shape.
  virtual double grad2(int c, const CellView& view) const = 0;
  /// @brief A burning cell is on the fringe when a neighbour inside is still unburnt (state 0).
  virtual bool on_fringe(int c, const std::vector<std::uint8_t>& state) const = 0;

  /// @brief Ignite cell c at time t0 (>= front_time()).
  virtual void ignite(int c, double t0, const SpreadLaw& law, const CellView& view) = 0;
  /// @brief Ignite the point `offset` (world axes, m) away from cell c's centre now; the grid
  /// lights the cell itself, as the paper's cellular rule does.
  virtual void ignite_point(int c, const Eigen::Vector3d& offset, double t0, const SpreadLaw& law,
                            const CellView& view) {
    (void)offset;
    ignite(c, t0, law, view);
  }
  /// @brief Accept, in time order, every cell whose arrival time is <= t_end.
  virtual const std::vector<int>& advance(double t_end, const SpreadLaw& law, const CellView& view) = 0;
  virtual const std::vector<double>& arrival() const = 0;
  /// @brief Cells in the front's narrow band (its active set).
  virtual std::size_t num_trial() const = 0;
  virtual double front_time() const = 0;

  /// @brief Interpolate a per-cell field at every input vertex.
  virtual void cells_to_vertices(const double* cell_values, double* out) const = 0;
  /// @brief Per input vertex, the cell whose events (ignition, burn-out) it shows.
  virtual const std::vector<int>& vertex_cell() const = 0;
};

/// @brief The paper's grid (Sheet) and its fronts (FireFront).
class GridCells final : public FireCells {
 public:
  GridCells(std::shared_ptr<const Sheet> sheet, FrontMethod method);
  std::unique_ptr<FireCells> clone() const override { return std::make_unique<GridCells>(*this); }

  const Sheet& sheet() const { return *sheet_; }
  int size() const override { return sheet_->num_cells(); }
  const std::vector<std::uint8_t>& inside() const override { return sheet_->inside(); }
  Eigen::Vector3d rest(int c) const override { return sheet_->cell_rest().row(c).transpose(); }
  Eigen::Vector3d rest_normal(int c) const override { return sheet_->cell_rest_normal().row(c).transpose(); }
  double area(int) const override { return sheet_->du() * sheet_->dv(); }
  double spacing() const override;
  double reach() const override;
  double total_area() const override { return sheet_->area(); }
  double noise(int c, std::uint64_t seed, std::uint64_t stream) const override;
  /// @brief The cell's normal now, from its grid neighbours' positions (view.position).
  Eigen::Vector3d normal_from_neighbours(int c, const CellView& view) const;
  double grad2(int c, const CellView& view) const override;
  bool on_fringe(int c, const std::vector<std::uint8_t>& state) const override;
  void ignite(int c, double t0, const SpreadLaw& law, const CellView& view) override;
  const std::vector<int>& advance(double t_end, const SpreadLaw& law, const CellView& view) override;
  const std::vector<double>& arrival() const override { return front_.arrival(); }
  std::size_t num_trial() const override { return front_.num_trial(); }
  double front_time() const override { return front_.time(); }
  void cells_to_vertices(const double* cell_values, double* out) const override {
    sheet_->cells_to_vertices(cell_values, out);
  }
  const std::vector<int>& vertex_cell() const override { return sheet_->vertex_cell(); }
  /// @brief Eq 1's speed with the drive in grid axes (row, column tangents now).
  LocalSpeed local_speed(int c, const SpreadLaw& law, const CellView& view) const;

 private:
  SpeedFn speed_fn(const SpreadLaw& law, const CellView& view) const;
  std::shared_ptr<const Sheet> sheet_;
  FireFront front_;
};

/// @brief Cells on the shell's surface (SurfaceCells) and the surface front (SurfaceFront).
class ShellCells final : public FireCells {
 public:
  /// @param cells about cells^2 cells over the mesh's area, as the grid's N.
  ShellCells(const RowMatX3& vertices, const RowMatX3i& faces, int cells);
  std::unique_ptr<FireCells> clone() const override { return std::make_unique<ShellCells>(*this); }

  const SurfaceCells& surface() const { return *cells_; }
  int size() const override { return cells_->size(); }
  const std::vector<std::uint8_t>& inside() const override { return inside_; }
  Eigen::Vector3d rest(int c) const override { return cells_->positions()[c]; }
  Eigen::Vector3d rest_normal(int c) const override { return cells_->normals()[c]; }
  double area(int c) const override { return cells_->areas()[c]; }
  double spacing() const override { return cells_->spacing(); }
  double reach() const override { return 3.0 * cells_->spacing(); }
  double total_area() const override { return cells_->total_area(); }
  double noise(int c, std::uint64_t seed, std::uint64_t stream) const override;
  double grad2(int c, const CellView& view) const override;
  bool on_fringe(int c, const std::vector<std::uint8_t>& state) const override;
  void ignite(int c, double t0, const SpreadLaw& law, const CellView& view) override;
  /// The point carried to the rest surface by the cell's own displacement, then projected on
  /// the nearest cell's tangent plane there (SurfaceFront::ignite_point): a source between
  /// cells is not snapped to one.
  void ignite_point(int c, const Eigen::Vector3d& offset, double t0, const SpreadLaw& law,
                    const CellView& view) override;
  const std::vector<int>& advance(double t_end, const SpreadLaw& law, const CellView& view) override;
  const std::vector<double>& arrival() const override { return front_.arrival(); }
  std::size_t num_trial() const override { return front_.num_trial(); }
  double front_time() const override { return front_.time(); }
  void cells_to_vertices(const double* cell_values, double* out) const override;
  const std::vector<int>& vertex_cell() const override { return vertex_cell_; }
  /// @brief Eq 1's speed, the drive read on the cell's tangent plane now and carried back to
  /// its rest tangent plane, where the front marches.
  SurfaceSpeed local_speed(int c, const SpreadLaw& law, const CellView& view) const;

 private:
  SurfaceSpeedFn speed_fn(const SpreadLaw& law, const CellView& view) const;
  std::shared_ptr<const SurfaceCells> cells_;
  SurfaceFront front_;
  std::vector<std::uint8_t> inside_;
  std::vector<int> vertex_cell_;
  double noise_scale_;  // m between the noise's nodes
};

}  // namespace thinburn
