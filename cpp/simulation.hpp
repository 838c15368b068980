#pragma once
/// @brief The whole model, stepped in time: cells and fire front (paper §3), fire particles,
/// heat and pyrolysis (§4.2), the FFD lattice and its motion (§4.1, §4.3).
#include "bending.hpp"
#include "cell_locator.hpp"
#include "dynamics.hpp"
#include "fire_cells.hpp"
#include "fire_front.hpp"
#include "lattice.hpp"
#include "particles.hpp"
#include "phase_times.hpp"
#include "sheet.hpp"
#include "shell.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

namespace thinburn {

/// @brief Cell states, as in the paper §3.1.
enum CellState : std::uint8_t { kUnburnt = 0, kBurning = 1, kBurnt = 2 };

/// @brief Where the fire's cells and the lattice live (issue #11; docs/surface_front.md).
enum class Geometry {
  Auto,    ///< Plane for a flat mesh, Surface for any other
  Plane,   ///< the paper's N x N grid over the rest plane (or UV) and an M x M lattice
  Surface  ///< cells on the surface itself and a lattice on a control surface fitted to it
};

/// The largest lattice, M couples per side: a step costs about M^2 (python/thinburn/simulation.py,
/// MAX_LATTICE, has the measurements).
constexpr int kMaxLattice = 129;

/// @brief Every scalar the simulation needs; the Python layer fills it from a material preset.
struct SimulationParams {
  int cells = 128;
  Geometry geometry = Geometry::Auto;
  FrontMethod front = FrontMethod::Fmm2;  ///< the grid's front (Plane); Surface has its own
  std::uint64_t seed = 0;
  // Spread (eq 1): V = V0·(1 − Cv·grad²), floored at v_floor·V0.
  double v0 = 0.0035;          ///< m/s
  double cv = 0.5;             ///< eq 1 spread coefficient
  double v_floor = 0.05;       ///< fraction of V0 below which V never falls
  double speed_noise = 0.0;    ///< relative per-cell jitter of V0 (seeded), breaks grid symmetry
  double burn_duration = 4.0;  ///< s a cell burns before it is burnt
  /// s from the first ignition until every cell the fire can reach has burnt out; 0: off, the
  /// material's speed (docs/fire_front.md, "Finishing within a time").
  double finish_within = 0.0;
  // Heat ignites (eq 2 at the cells; docs/heat.md, "Heat ignites"). 0: off.
  double ignition_temperature = 0.0;  ///< K above ambient at which an unburnt cell catches fire
  double ignition_gain = 0.0;         ///< eq 2's Ct for the cells' temperature, m^2/s
  double heat_loss = 0.3;             ///< 1/s, the cells' cooling (Newton's law)
  double duration_noise = 0.0; ///< relative per-cell jitter of the burn duration
  // Direction-dependent spread (beyond the paper; 0 keeps eq 1 symmetric).
  double climb = 0.0;          ///< drive toward world-up along the sheet, |e| per unit slope
  double wind_spread = 0.0;    ///< drive per m/s of wind along the sheet
  double max_drive = 0.9;      ///< cap on |e| so the back fire never stalls completely
  // Mass: burnt cells lose mass and turn to ash.
  double areal_density = 0.045;  ///< kg/m^2
  double ash_fraction = 0.1;     ///< share of the mass a burnt cell keeps
  double ash_strength = 0.1;     ///< share of the lattice springs' stiffness burnt sheet keeps
  // The shell: lattice, particles, bending and motion (paper §4). Off: the sheet keeps its rest shape.
  bool shell = true;
  int lattice = 0;               ///< M couples per side; 0 chooses from the sheet's size and N
  double lattice_thickness = 0;  ///< m between a couple's two vertices; 0 chooses
  double crease_angle = kDefaultCreaseAngle;  ///< ShellParams::crease_angle
  bool has_floor = false;        ///< a horizontal floor (a table) under the sheet
  double floor_z = 0.0;          ///< m, its height
  /// Share of the sheet's size a couple drifts before the mesh vertices it carries are redone;
  /// each vertex is then within twice that of its exact place (0: exact, bit for bit).
  double mesh_tolerance = kDefaultMeshTolerance;
  /// Share of the sheet's size it starts bowed by along its normals (ShellParams::imperfection).
  double imperfection = kDefaultImperfection;
  DynamicsParams dynamics;
  ParticleParams particles;
  BendingParams bending;

  /// @brief The table of the scalars (the groups have their own) (param_table.hpp): names, bounds, docs.
  static const std::vector<param::Field<SimulationParams>>& fields();
};

/// @brief Throw std::invalid_argument naming the first invalid field (its groups' too).
void validate(const SimulationParams& p);

/// @brief Painted maps, one value >= 0 per input vertex; an empty map is 1 everywhere (and
/// costs nothing: the simulation is bit-identical to one without it). Read at the cells by
/// vertex_field_at_cells. 0 in either map is a firebreak: the cell never burns.
struct CellMaps {
  Eigen::VectorXd speed;  ///< multiplies V0 (eq 1)
  Eigen::VectorXd fuel;   ///< multiplies the burn duration
};

class Simulation {
 public:
  /// @param pinned per input vertex, nonzero = held in place (may be empty).
  /// @param maps painted speed and fuel (docs/fire_front.md, "Painted maps").
  Simulation(const RowMatX3& vertices, const RowMatX3i& faces, const RowMatX2& uv,
             const SimulationParams& params, const std::vector<std::uint8_t>& pinned = {},
             const CellMaps& maps = {});

  /// @brief Ignite the inside cells within radius of a point (the nearest one when radius is 0)
  /// at time t; firebreak cells within it stay unlit. Throws std::invalid_argument when no cell
  /// lies within reach of the point.
  /// @return the number of cells lit (0 when all of them are firebreaks).
  int ignite(const Eigen::Vector3d& point, double t, double radius);
  /// @brief Ignite the given cells at time t (firebreaks, cells outside the sheet and cells
  /// already alight are skipped). @return the number lit.
  int ignite_cells(const std::vector<int>& cells, double t);
  /// @brief Ignite every unburnt cell within radius of any of the points now (a mesh igniter's
  /// surface, sampled); points may lie anywhere. @return the number lit.
  int ignite_near(const RowMatX3& points, double radius, double t);
  /// @brief A per-vertex field read at every cell (vertex_field_at_cells).
  std::vector<double> vertex_field(const Eigen::VectorXd& values) const;
  /// @brief Multiplies every cell's speed from now on (1: as the material says); > 0. For a
  /// burn timed to a duration (docs/fire_front.md, "Burn duration").
  void set_speed_scale(double s);
  double speed_scale() const { return speed_scale_; }
  /// @brief The cells ignite(point, t, radius) would light, ascending; throws as ignite does.
  std::vector<int> cells_near(const Eigen::Vector3d& point, double radius) const;
  /// @brief Advance by dt seconds (dt > 0). Atomic: a step that throws (an explicit integrator
  /// that would need more than max_substeps) leaves the Simulation exactly as it was.
  void step(double dt);

  double time() const { return time_; }
  /// @brief Plane or Surface (never Auto): the geometry chosen.
  Geometry geometry() const { return grid_ ? Geometry::Plane : Geometry::Surface; }
  /// @brief The cells and their front.
  const FireCells& fire_cells() const { return *cells_; }
  int num_cells() const { return cells_->size(); }
  /// @brief The grid sheet (Plane); throws std::invalid_argument on a Surface simulation.
  const Sheet& sheet() const;
  /// @brief The surface cells (Surface); throws std::invalid_argument on a Plane simulation.
  const SurfaceCells& surface_cells() const;
  /// @brief The input mesh's vertices (rest).
  const RowMatX3& vertices() const { return vertices_; }
  const SimulationParams& params() const { return params_; }
  void set_wind(const Eigen::Vector3d& w) { wind_ = w; }
  /// @brief Wind per control vertex for the sheet's motion (the lattice's (2 M^2) x 3 rows, as
  /// lattice_positions; 0 rows: the uniform wind again). The fire and the particles keep the
  /// uniform wind. Needs shell.
  void set_wind_field(const RowMatX3& w) {
    if (!shell_) throw std::invalid_argument("set_wind_field: this simulation has no shell");
    shell_->set_wind_field(w);
  }
  /// @brief Collision objects for the sheet's motion (Shell::set_colliders); null: none.
  /// samples: contact points of the sheet per control cell side (0: control vertices only).
  /// Needs shell.
  void set_colliders(std::shared_ptr<const Colliders> c, double margin, int samples = 0) {
    if (!shell_) throw std::invalid_argument("set_colliders: this simulation has no shell");
    shell_->set_colliders(std::move(c), margin, samples);
  }
  const Eigen::Vector3d& wind() const { return wind_; }

  std::vector<std::uint8_t> cell_states() const { return state_; }
  std::vector<double> ignition_times() const;
  std::vector<double> burn_durations() const { return duration_; }
  /// @brief Fringe cells (paper §3.1): burning cells with a neighbour neither burning nor burnt.
  std::vector<int> fringe() const;
  void fringe_into(std::vector<int>& out) const;
  /// @brief Flames that burn on their own (a candle): each point emits fire particles as a
  /// burning front of that length would (upward), every step until replaced; empty: none.
  /// Needs the shell (its particles). Their heat bends the sheet (eq 2) and, with heat
  /// ignition, lights it.
  void set_fire_sources(const RowMatX3& points, const Eigen::VectorXd& lengths);
  /// @brief Per cell, its temperature above ambient from the fire particles (eq 2 with
  /// ignition_gain, cooling at heat_loss), K; empty when heat ignition is off.
  const std::vector<double>& cell_temperature() const { return cell_temp_; }
  /// @brief Per cell, its connected piece of the sheet (heat ignition only; else empty).
  const std::vector<int>& cell_pieces() const { return piece_; }
  /// @brief 1 where a cell can never burn (a painted 0 in the speed or fuel map).
  bool is_firebreak(int cell) const { return v_scale_[cell] == 0.0; }
  /// @brief Char per cell in [0, 1]: 0 before ignition, rising over the burn, 1 when burnt.
  std::vector<double> cell_char() const;
  /// @brief Remaining mass per cell, kg.
  std::vector<double> cell_mass() const { return mass_; }
  /// @brief Current positions of the cell centres (one row per cell).
  RowMatX3 cell_positions() const;
  RowMatX3 vertex_positions() const;
  /// @brief vertex_positions into a caller's n x 3 rows; throws std::invalid_argument naming
  /// `out` when its row count is not the mesh's.
  void vertex_positions_into(Eigen::Ref<RowMatX3> out) const;
  /// @brief Where points of the rest mesh are now: row i is sum_k w(i, k) * vertex idx(i, k)
  /// at rest, mapped as the vertices are (Shell::mesh_points; without a shell, at rest). Throws
  /// std::invalid_argument naming `vertices` or `weights` when their shapes differ or an
  /// index is not a vertex's.
  RowMatX3 mesh_points(const Eigen::Ref<const RowMatXi>& idx, const Eigen::Ref<const RowMatXd>& w) const;
  Eigen::VectorXd vertex_char() const;
  Eigen::VectorXd vertex_ignition_times() const;
  Eigen::VectorXd vertex_burnout_times() const;
  /// @brief Cells in the front's narrow band: the active set of the eikonal solver.
  std::size_t front_active() const { return cells_->num_trial(); }
  std::size_t num_burning() const { return burning_.size(); }
  /// @brief The local spread law at a cell now (eq 1 and the drive vector in grid axes; Plane).
  LocalSpeed local_speed(int cell) const;
  /// @brief Eq 1's speed at a cell now, m/s (either geometry).
  double cell_speed(int cell) const;
  /// @brief Unit normal of a cell now.
  Eigen::Vector3d cell_normal(int cell) const;
  /// @brief grad² at a cell: squared slope of the current surface out of the rest plane.
  double grad2(int cell) const;

  bool has_shell() const { return shell_ != nullptr; }
  int lattice_size() const { return shell_ ? shell_->size() : 0; }
  double lattice_thickness() const { return shell_ ? shell_->thickness() : 0.0; }
  /// @brief Shell::layer_fit: how far (p99, in half-thicknesses) the mesh lies from its layer's
  /// mid-surface; 0 on a grid lattice or without a shell.
  double lattice_fit() const { return shell_ ? shell_->layer_fit() : 0.0; }
  /// @brief The lattice's own flexural rigidity and the share of it its layers keep
  /// (LatticeDynamics::lattice_rigidity, bending_share); 0 and 1 without a shell.
  double lattice_rigidity() const { return shell_ ? shell_->dynamics().lattice_rigidity() : 0.0; }
  double bending_share() const { return shell_ ? shell_->dynamics().bending_share() : 1.0; }
  /// @brief Couples of the lattice (M^2 on a grid).
  int lattice_couples() const { return shell_ ? shell_->couples() : 0; }
  /// @brief Control vertices (2 couples x 3), index 2 couple + k, k = 1 top; on a grid
  /// couple = i*M + j.
  const RowMatX3& lattice_positions() const;
  /// @brief The shell's parts (null without a shell).
  const Shell* shell() const { return shell_.get(); }
  const Bending* bending() const { return shell_ ? &shell_->bending() : nullptr; }
  const FfdLattice* lattice() const { return shell_ ? &shell_->lattice() : nullptr; }
  const ParticleSystem* particles() const { return shell_ ? &shell_->particles() : nullptr; }
  const LatticeDynamics* dynamics() const { return shell_ ? &shell_->dynamics() : nullptr; }
  const StepStats& last_step_stats() const;
  /// @brief Per-control-vertex masses now (kg).
  const Eigen::VectorXd& control_masses() const;
  void set_dynamics_params(const DynamicsParams& p);
  /// @brief Wall-clock seconds per phase of the steps and vertex_positions calls so far.
  PhaseTimes phase_times() const;

 private:
  Eigen::Vector3d cell_position(int cell) const;
  struct Saved;
  bool step_may_throw() const;
  void step_unguarded(double dt);
  Saved save() const;
  void restore(Saved&& saved);
  void build_locator();
  void refresh_locator() const;
  void retire_burnt();
  ShellParams shell_params() const;
  void show_floor_in_dynamics();
  void step_shell(double dt);
  void gather_shell_sources();
  double flame_side(int cell) const;
  void bind_cells();
  void refresh_law();
  Eigen::Vector3d drive() const;  // eq 1's world drive now: climb and wind
  double noise(int cell, std::uint64_t stream) const;
  void apply_maps(const RowMatX3i& faces, const CellMaps& maps);
  std::vector<int> scan_cells_near(const Eigen::Vector3d& point, double radius, double* nearest_distance, int* nearest) const;

  // The pace of a burn timed by finish_within: the rest-shape arrival times tau (slope factor
  // and drive off, scale 1) from the sources so far, and the feedback on how fast the fire
  // really covers them.
  struct Pace {
    std::vector<int> sources;    // cells lit by ignite calls, ascending
    bool stale = false;          // sources changed since tau was solved
    double t0 = -1.0;            // the first ignition, s (< 0: none yet)
    std::vector<double> tau;     // per cell, s; inf where the fire cannot reach
    std::vector<int> order;      // reachable cells by tau
    std::vector<double> cum;     // their areas, summed in that order
    double window = 0.0;         // s from t0 by which the last cell must ignite
    double covered = 0.0;        // tau covered, decayed over the feedback's window
    double scaled = 0.0;         // seconds of speed scale spent, decayed alike
    double prev_tau = 0.0, prev_dt = 0.0;
    bool has_prev = false;       // false: the next step sets the scale outright
  };
  void note_sources(const std::vector<int>& lit, double t0);
  void find_pieces();
  void find_outsides(int pieces);
  void heat_ignite(double dt);
  RowMatX3 source_pos_;
  Eigen::VectorXd source_len_;
  std::vector<double> cell_temp_;
  std::vector<int> piece_;
  std::vector<std::uint8_t> piece_alight_;
  std::vector<double> piece_outside_;  // per piece: +1/-1 the side of its normals facing out of a closed piece, 0 open
  void replan();
  double tau_covered() const;
  void pace_step(double dt);

  SimulationParams params_;
  RowMatX3 vertices_;
  Pace pace_;
  std::unique_ptr<FireCells> plan_cells_;  // pristine cells for the pace's solves
  RowMatX3i faces_;
  double speed_scale_ = 1.0;
  std::unique_ptr<FireCells> cells_;
  const GridCells* grid_ = nullptr;    // cells_ when it is the grid
  const ShellCells* surface_ = nullptr;  // cells_ when it is on the surface
  SpreadLaw law_;
  CellView view_;
  double time_ = 0.0;
  Eigen::Vector3d wind_ = Eigen::Vector3d::Zero();
  std::vector<std::uint8_t> state_;
  std::vector<double> duration_;
  std::vector<double> v_scale_;  // per-cell V0 multiplier (seeded noise)
  std::vector<double> mass_;
  std::vector<int> burning_;     // the cells burning now: an active list, never a sweep
  std::vector<int> fringe_buf_;
  // The shell (null when params.shell is off), and the sources the fire hands it each step.
  std::unique_ptr<Shell> shell_;
  RowMatX3 emit_pos_, emit_normal_, ignition_pts_;
  Eigen::VectorXd emit_len_, emit_side_;
  // Nearest-cell queries for ignite; its displacement bounds follow the lattice lazily.
  std::unique_ptr<CellLocator> locator_;
  mutable bool locator_stale_ = true;
  PhaseTimes times_;  // the fire's phases; the shell keeps its own
};

}  // namespace thinburn
