#pragma once
/// @brief The shell half of the model (paper §4): the FFD lattice draped over the sheet, the
/// cells' mass and area mapped onto its couples, fire particles, heat (eq 2), pyrolysis (eq 3),
/// the rotation D (eqs 4-6) and the lattice's motion (eqs 7-15).
///
/// The Shell knows the sheet's geometry but nothing of the fire's rules: each step the
/// Simulation hands it the emitters (fringe cells) and the ignition points (burning cells on
/// their flame face), and tells it when a cell burns out.
#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

#include "bending.hpp"
#include "control_surface.hpp"
#include "dynamics.hpp"
#include "fold_blend.hpp"
#include "lattice.hpp"
#include "outside_keeper.hpp"
#include "particles.hpp"
#include "phase_times.hpp"
#include "sheet.hpp"
#include "surface_cells.hpp"

namespace thinburn {

using RowMatXi = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using RowMatXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Share of the sheet's size a couple may drift before the mesh's vertices it carries are redone
/// (CachedDeform's tolerance over the sheet's larger side): a vertex then lags its exact place
/// by at most twice that, 2 um on a 1 m sheet, far below a pixel (docs/lattice.md, "The mesh's
/// tolerance").
constexpr double kDefaultMeshTolerance = 1e-6;
/// The sheet's crookedness at the start, as a share of its size: engineering's L/1000 for a
/// column's initial bow (docs/dynamics.md §1.2).
constexpr double kDefaultImperfection = 1e-3;

/// @brief What the shell needs of the simulation's parameters.
struct ShellParams {
  int lattice = 0;               ///< M couples per side; 0 chooses from the sheet's size and N
  double lattice_thickness = 0;  ///< m between a couple's two vertices; 0 chooses
  /// Degrees: a curved shell's mesh edges turning by more are creases (180: none).
  double crease_angle = kDefaultCreaseAngle;
  bool has_floor = false;
  double floor_z = 0.0;
  double ash_strength = 0.1;     ///< share of the springs' stiffness burnt sheet keeps
  double mesh_tolerance = kDefaultMeshTolerance;  ///< of the sheet's size; 0: the mesh is exact
  /// The sheet's crookedness at the start: its couples bowed along their normals by this share
  /// of its size at the centre (docs/dynamics.md §1.2). No sheet is flat; a perfectly flat one
  /// pinned along its bottom would stand in its plane for ever, however tall.
  double imperfection = kDefaultImperfection;
  std::uint64_t seed = 0;
  DynamicsParams dynamics;
  ParticleParams particles;
  BendingParams bending;

  /// @brief The table of the scalars (the groups have their own) (param_table.hpp): names, bounds, docs.
  static const std::vector<param::Field<ShellParams>>& fields();
};

/// @brief Throw std::invalid_argument naming the first invalid field (its groups' too).
void validate(const ShellParams& p);

/// @brief The fire's sources for one step of the shell.
struct ShellSources {
  const RowMatX3* emit_pos;          ///< fringe cells' positions (k x 3)
  const RowMatX3* emit_normal;       ///< their flame-side normals
  const Eigen::VectorXd* emit_len;   ///< front length each stands for, m
  const RowMatX3* ignition_points;   ///< burning cells on their flame face (eq 3)
  const Eigen::VectorXd* emit_side = nullptr;  ///< per emitter: +1/-1 the flame's side, 0 the up rule
};

class Shell {
 public:
  /// @brief The paper's shell: an M x M grid lattice over a flat sheet's cells.
  /// @param cell_mass per cell, kg (0 outside the sheet); @param pinned per input vertex,
  /// nonzero = held in place (may be empty).
  Shell(const Sheet& sheet, const ShellParams& params, const std::vector<double>& cell_mass,
        const std::vector<std::uint8_t>& pinned);
  /// @brief Any shell: a lattice on a control surface fitted to the mesh (control_surface.hpp),
  /// over cells on the surface itself. params.lattice counts couples along sqrt(area).
  Shell(const SurfaceCells& cells, const RowMatX3& vertices, const RowMatX3i& faces,
        const ShellParams& params, const std::vector<double>& cell_mass,
        const std::vector<std::uint8_t>& pinned);
  // The floor support reads this shell's control surface through a pointer to it.
  Shell(const Shell&) = delete;
  Shell& operator=(const Shell&) = delete;

  /// @brief M couples per side on a grid lattice, 0 on a control surface.
  int size() const { return M_; }
  int couples() const { return lattice_->couples(); }
  double thickness() const { return thickness_; }
  /// @brief How well the lattice carries the mesh: the 99th percentile over mesh vertices of
  /// their distance from the control surface's interpolated mid-surface over half the layer's
  /// thickness (<= 1: in the layer). 0 on a grid lattice, whose mesh lies on it.
  double layer_fit() const { return layer_fit_; }
  /// @brief The control surface (null on a grid lattice).
  const ControlSurface* control_surface() const { return control_.get(); }

  /// @brief Grid lattice: the couples a cell's centre sits between and their bilinear weights.
  void cell_couples(int cell, int* couple, double* w) const;
  /// @brief A cell centre's position now (mid-thickness of the lattice).
  Eigen::Vector3d cell_position(int cell) const;
  /// @brief Control surface: the layer's normal at a cell now (bottom -> top).
  Eigen::Vector3d cell_normal(int cell) const;
  /// @brief A normal at a cell turned as its piece of the shell turned as a whole (its best
  /// rigid rotation since rest; a grid lattice is one piece).
  Eigen::Vector3d turned_rest_normal(int cell, const Eigen::Vector3d& rest_normal) const;
  /// @brief Grid lattice: per control cell ((M-1)^2 rows), the lowest and highest
  /// displacement its cells can have now: their four couples' extremes.
  void quad_displacement_bounds(RowMatX3& lo, RowMatX3& hi) const;

  /// @brief A cell burnt out: it loses mass to ash and its share of the lattice's strength.
  void cell_burnt(int cell, double mass_lost);
  /// @brief One step: particles from the emitters, heat, pyrolysis, D and the motion.
  void step(double dt, const ShellSources& sources, const Eigen::Vector3d& wind);

  /// @brief Deformed mesh vertices, raised to the floor where it has one.
  void vertex_positions(RowMatX3& out) const;
  /// @brief The same into a caller's n x 3 rows (no allocation on a grid lattice).
  void vertex_positions_into(Eigen::Ref<RowMatX3> out) const;
  /// @brief Where points of the rest mesh are now, mapped as its vertices are: on a grid
  /// lattice the spline, where the lattice folds its couples, and the floor; on a control
  /// surface each point embedded as a vertex is (from the seed of its weightiest vertex), and
  /// the floor. Row i of the rest points is sum_k w(i, k) * vertex idx(i, k) at rest (indices
  /// checked by the caller).
  void mesh_points(const Eigen::Ref<const RowMatXi>& idx, const Eigen::Ref<const RowMatXd>& w,
                   RowMatX3& out) const;
  /// @brief Mesh vertices the last vertex_positions call recomputed (a grid lattice keeps the
  /// others from the call before: their couples had not moved); -1 on a control surface.
  long mesh_points_redone() const { return mesh_deform_ ? mesh_deform_->points_redone() : -1; }

  void set_dynamics_params(const DynamicsParams& p);
  /// @brief Per-control-vertex wind for the motion (LatticeDynamics::set_wind_field).
  void set_wind_field(const RowMatX3& w) { dynamics_->set_wind_field(w); }
  /// @brief Collision objects for the motion (LatticeDynamics::set_colliders). samples: contact
  /// points per control cell side, in [0, kMaxContactSamples] (0: the control vertices only); a
  /// grid lattice's, on the sheet's mid-surface where the sheet is (contact_samples); a control
  /// surface's, mesh vertices about a control spacing / samples apart (surface_contact_samples).
  void set_colliders(std::shared_ptr<const Colliders> c, double margin, int samples = 0);
  static constexpr int kMaxContactSamples = 16;

  const FfdLattice& lattice() const { return *lattice_; }
  const LatticeDynamics& dynamics() const { return *dynamics_; }
  const ParticleSystem& particles() const { return *particles_; }
  const Bending& bending() const { return *bending_; }
  const StepStats& last_step_stats() const { return stats_; }
  /// @brief Per-control-vertex masses now (kg).
  const Eigen::VectorXd& control_masses() const { return control_mass_; }
  /// @brief Wall-clock seconds per phase of the shell's steps and mesh deforms so far.
  const PhaseTimes& phase_times() const { return times_; }

  /// @brief Everything a step changes, for a step that may have to be undone.
  struct Checkpoint;
  Checkpoint checkpoint() const;
  void rollback(Checkpoint&& c);

 private:
  RowMatX3 drape() const;
  ContactSamples contact_samples(int per_cell) const;
  ContactSamples surface_contact_samples(int per_cell) const;  // a control surface's
  static std::vector<int> spread_points(const RowMatX3& points, double spacing);
  void bilinear_couples(double s, double t, int* couple, double* w) const;
  bool rest_is_flat() const;
  template <class F>
  void for_cell_shares(int cell, F&& f) const;  // f(couple, share) over the couples carrying the cell
  void add_cell_mass(int cell, double dm);
  void add_cell_area(int cell, Eigen::VectorXd& onto) const;  // half to each layer
  void finish(const std::vector<double>& cell_mass, int num_cells, const std::vector<std::uint8_t>& inside,
              const LatticeTopology& topology, double per_paper_cell);
  void pin(const std::vector<std::uint8_t>& pinned);
  void bow();
  void set_floor_offsets();
  void set_centre_floor();
  void find_pieces();
  void piece_seeds(const SurfaceCells& cells, const RowMatX3i& faces, std::vector<int>* vertex_seed,
                   std::vector<int>* cell_seed) const;
  void update_piece_rotations();
  void keep_flames_outside(double dt);
  void hand_over_masses_and_strength();

  const Sheet* sheet_ = nullptr;              // grid lattice
  std::unique_ptr<ControlSurface> control_;   // control surface
  SurfaceEmbedding surface_vertices_, surface_cells_;
  std::vector<int> vertex_seed_;               // control surface: per mesh vertex, its embedding's seed couple
  std::vector<double> cell_area_;
  std::vector<int> piece_of_;                  // per couple, its connected piece
  std::vector<int> cell_piece_;                // control surface: per fire cell, its piece
  std::vector<Eigen::Matrix3d> piece_rotation_;  // per piece: its rigid rotation since rest
  std::unique_ptr<OutsideKeeper> outside_keeper_;  // control surface: flames stay out of closed pieces
  Eigen::VectorXd couple_burnt_;                 // per couple, its burnt share (outside_keeper_)
  ShellParams params_;
  int M_ = 0;
  LatticeInterp mesh_interp_ = LatticeInterp::Trilinear;  // in-plane FFD of a grid lattice's mesh and cells
  double layer_fit_ = 0.0;
  double thickness_ = 0.0;
  std::unique_ptr<FfdLattice> lattice_;
  std::unique_ptr<LatticeDynamics> dynamics_;
  std::unique_ptr<ParticleSystem> particles_;
  std::unique_ptr<Bending> bending_;
  Embedding vertex_embedding_;
  // The mesh's deformed vertices kept between frames: only those near moving couples are
  // redone (a grid lattice's mesh; vertex_positions is const, the pointer shallow).
  std::unique_ptr<CachedDeform> mesh_deform_;
  std::unique_ptr<FoldBlend> fold_blend_;  // a flat sheet's mesh where its lattice folds (null: none; mesh_mutex_)
  Eigen::VectorXd control_mass_, control_area_, burnt_area_, strength_;
  bool mass_dirty_ = false;
  bool strength_dirty_ = false;
  StepStats stats_;
  mutable PhaseTimes times_;  // mutable: vertex_positions (const) times the mesh
  mutable std::mutex mesh_mutex_;  // vertex_positions: one at a time (its timer, its cache)
  RowMatX3 particle_pos_;
  Eigen::VectorXd particle_temp_, rotation_, applied_rotation_;
};

struct Shell::Checkpoint {
  Eigen::VectorXd control_mass, burnt_area, strength, applied_rotation;
  std::vector<Eigen::Matrix3d> piece_rotation;
  bool mass_dirty, strength_dirty;
  StepStats stats;
  std::unique_ptr<ParticleSystem> particles;
  std::unique_ptr<Bending> bending;
  RowMatX3 lattice;
  LatticeDynamics::Checkpoint dynamics;
};

}  // namespace thinburn
