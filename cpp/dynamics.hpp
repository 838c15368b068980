#pragma once
/// @brief Motion of the FFD lattice (Liu et al. 2009 §4.3, eqs 7-15): springs, crumple,
/// damping, gravity, buoyancy, wind and a floor, integrated explicitly (the paper's scheme),
/// with symplectic Euler or with Baraff-Witkin backward Euler, on the awake vertices only.
///
/// Units: SI (m, kg, s), z up. See docs/dynamics.md for every reading and choice.
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <cstdint>
#include <memory>
#include <vector>

#include "bimetal.hpp"
#include "colliders.hpp"
#include "contact.hpp"
#include "implicit_solver.hpp"
#include "lattice.hpp"
#include "membrane.hpp"
#include "param_table.hpp"
#include "self_contact.hpp"
#include "sleeping.hpp"
#include "strain_limit.hpp"

namespace thinburn {

/// @brief Time integrator of the lattice.
enum class Integrator {
  Explicit,    ///< the paper's eqs 13-15: V = V0 + a dt, Pos = Pos0 + V dt + a dt^2 / 2
  Symplectic,  ///< symplectic Euler: V = V0 + a dt, Pos = Pos0 + V dt
  Implicit,    ///< backward Euler (first order), one Newton step per substep, a linear solve each
  Bdf2         ///< BDF2 (second order), one Newton step per substep, a linear solve each
};

/// @brief True for the integrators that solve a linear system per substep.
inline bool is_implicit(Integrator i) { return i == Integrator::Implicit || i == Integrator::Bdf2; }

/// @brief Preconditioner of the implicit integrator's conjugate gradients.
enum class Preconditioner {
  Auto,   ///< Ldlt up to ldlt_max_vertices awake vertices; above, the one that measurably costs less
  Ldlt,   ///< a sparse block LDL^T factorization of the system (block_ldlt.hpp), kept until it goes stale
  Jacobi  ///< couple-block Jacobi (each couple's 6 x 6 block inverted), rebuilt every substep
};

/// Bounds where a step's cost explodes (each substep is a sweep, implicit: a linear solve, over
/// the awake lattice; measured 7-60 us at M = 4, 0.3 s implicit at M = 33): a fixed substep
/// count runs every substep, max_substeps only caps what an explicit step may ask for.
constexpr int kMaxFixedSubsteps = 10000;
constexpr int kMaxSubstepsCeiling = 1000000;
/// Where the membrane's knee lies, as a share of strain_limit: inside the limit, so that a
/// sheet at rest rests on the knee's stiffness, not on the limit's projection (whose resting
/// shape depends on the step; docs/dynamics.md §3.4, "The knee").
constexpr double kKneeShare = 0.8;

/// @brief Parameters of the lattice's motion; may change between steps.
struct DynamicsParams {
  double k_structure = 0.05;   ///< Table 1 coefficient of the axis-neighbour springs (per layer)
  double k_shear = 0.05;       ///< Table 1 coefficient of the diagonal springs (per layer)
  double k_flex = 0.05;        ///< Table 1 coefficient of the two-apart springs (per layer)
  double k_thickness = 1.0;    ///< coefficient of the top-bottom spring of each couple
  double k_transverse = 0.05;  ///< coefficient of the diagonals between adjacent couples' top and bottom
  double stiffness_unit = 1000.0;  ///< N/m per unit coefficient: spring k = coefficient * unit
  /// N m: the sheet's flexural rigidity B (a thin plate's E t^3 / 12 (1 - nu^2)). 0: the
  /// lattice's own, set by its layers' springs a thickness h apart (on a grid
  /// B = h^2 / 2 (k_structure + k_shear + 4 k_flex) unit); a smaller B splits each pair of layer
  /// springs into a membrane spring and a bending part (membrane.hpp); a larger one is the lattice's.
  double flexural_rigidity = 0.0;
  double c_damping = 1.7;      ///< 1/s, eq 12 per kilogram: F = -c_damping * m * v
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  ///< m/s^2
  double buoyancy = 1.0;       ///< N/kg per unit heat: F = m * buoyancy * heat * (0, 0, 1)
  double wind_drag = 1.0;      ///< Pa s/m: F = wind_drag * area * ((wind - v) . n) n
  bool has_floor = false;      ///< nothing goes below floor_z when set
  double floor_z = 0.0;        ///< m
  double friction = 0.5;       ///< Coulomb coefficient on the floor (>= 0)
  double slip_ratio = 3.0;     ///< implicit: a sticking floor contact the solve holds beyond slip_ratio x friction slides (docs/dynamics.md §3)
  bool self_collision = true;  ///< couples keep self_distance from the sheet's other layers (self_contact.hpp)
  double self_distance = 1.0;  ///< lattice thicknesses between a couple's mid-point and another part of the sheet (> 0)
  int contact_rounds = 3;      ///< while layers touch, turns of strain limit, floor and self-contact after a substep's self-contact (0: once, last)
  /// Largest |l / L - 1| of the distance between neighbouring couples' centres, kept after each
  /// substep (strain_limit.hpp); 0: no limit, in [0, 1).
  double strain_limit = 0.0;
  /// Coefficient (times stiffness_unit, N/m) by which a membrane spring stiffens beyond
  /// kKneeShare * strain_limit: the yarns straighten (docs/dynamics.md §3.4, "The knee"). Only
  /// where the sheet has a membrane (flexural_rigidity below the lattice's own); 0: none.
  double k_limit = 1.0;
  Integrator integrator = Integrator::Implicit;
  double crumple_gain = 1.0;   ///< multiplies the increase of D turned into a crumple (set_material: kCrumpleReferenceK / k_structure)
  double plasticity = 1.0;     ///< in [0, 1]: share of each crumple that the springs' rest lengths keep
  bool crumple_momentum = true;  ///< remove the crumple's net translation (it may bend, not move, the sheet)
  bool bimetal = true;         ///< D shrinks the heated face's springs (curvature gain * D / spacing); false: Fig. 5's prescribed chord motion
  bool anisotropic_curl = true;  ///< bimetal: the curl bends across the front (along grad D) only, not as a dome
  double sleep_speed = 1e-4;   ///< m/s: slower vertices, unforced, may sleep
  bool sleeping = true;        ///< false: every free vertex integrates every step
  /// Steps a flickering vertex stays awake: one that its neighbours' motion woke within this
  /// many steps of falling asleep. Vertices at the edge of a moving region otherwise fall asleep
  /// and are woken again step after step, each time redoing the step (a pass) and changing the
  /// active set (a new factorization). A vertex that flickers again is held twice as long. A
  /// batch of sleepers stressed awake in bulk within it holds off new batches as long (sleeping.hpp).
  int wake_hold = 12;
  int substeps = 0;            ///< 0: chosen per step from stability (explicit) or motion (implicit); <= kMaxFixedSubsteps
  int max_substeps = 10000;    ///< explicit steps needing more throw std::runtime_error; <= kMaxSubstepsCeiling
  double safety = 0.9;         ///< explicit substep h = safety * (theoretical stability limit)
  /// Implicit: largest relative change of a spring per substep. 1 lets a frame's crumple go in
  /// one substep (docs/dynamics.md); the conjugate gradients keep their 1e-8 relative residual:
  /// a looser solve (1e-4 was tried) leaves residual forces that, on light ash late in a burn,
  /// push the sheet tens of cm across the table.
  double max_stretch = 1.0;
  double cg_tolerance = 1e-8;  ///< relative residual of the conjugate gradients
  double cg_velocity_tolerance = 1e-7;  ///< m/s: absolute floor of the CG stopping test
  int cg_max_iterations = 2000;
  Preconditioner preconditioner = Preconditioner::Auto;
  int ldlt_max_vertices = 2500;    ///< Auto: the largest awake set given Ldlt without measuring
  int refactor_iterations = 100;   ///< Ldlt: a solve taking more iterations refactors for the next one (a ceiling: the rent rule refactors sooner)

  /// @brief The table of these fields (param_table.hpp): names, bounds, docs.
  static const std::vector<param::Field<DynamicsParams>>& fields();
};

/// @brief Throw std::invalid_argument naming the first invalid field and its bound.
void validate(const DynamicsParams& p);

/// Table 1's K_structure of paper (DynamicsParams' default k_structure), whose crumple gain is 1.
constexpr double kCrumpleReferenceK = 0.05;

/// @brief A Table 1 material's motion in p: its spring coefficients and damping, the transverse
/// diagonals (not in the paper) as stiff as the structure springs (they act as structure
/// springs between the layers), and crumple_gain = kCrumpleReferenceK / k_structure: D is a
/// thermal moment and a stiffer sheet answers it with less curvature (hard paper, ten times
/// stiffer than paper, bends a tenth as much: Fig. 10). Throws std::invalid_argument naming
/// Table 1's coefficient when k_structure is not > 0 or a coefficient is not finite and >= 0.
void set_material(DynamicsParams& p, double k_structure, double k_shear, double k_flex, double c_damping);

/// @brief Largest substep h for which an explicit integrator (Explicit or Symplectic) is
/// stable on every mode x'' = -w^2 x - c x' with w <= omega: spectral radius of the substep's
/// amplification matrix <= 1 (bisection). Undamped: Symplectic 2 / omega, Explicit sqrt(2) / omega.
double explicit_stability_limit(Integrator integrator, double omega, double c);

/// @brief What set a step's substeps (issue #12: substeps where accuracy needs them, and the
/// step says why). The last pass's; a redo overrides the count it started from.
enum class SubstepCause {
  None,         ///< nothing awake: no substep
  Set,          ///< DynamicsParams::substeps, the caller's fixed count
  One,          ///< nothing asked for more than one
  Stability,    ///< an explicit integrator's stability limit (Explicit, Symplectic)
  Accuracy,     ///< implicit: a spring would change by more than max_stretch in a substep
  Contact,      ///< a vertex near a collider must not fall through it (Contacts::contact_substeps)
  StretchRedo,  ///< the step ended with a spring overstretched and was redone with more
};
/// @brief "none", "set", "one", "stability", "accuracy", "contact", "stretch_redo".
const char* substep_cause_name(SubstepCause c);

/// @brief What one step did.
struct StepStats {
  int substeps = 0;       ///< substeps taken
  int awake = 0;          ///< vertices integrated
  int cg_iterations = 0;  ///< conjugate-gradient iterations, all substeps and passes
  int factorizations = 0; ///< block LDL^T factorizations (Ldlt preconditioner), all substeps and passes
  int ldlt_solves = 0;    ///< linear solves the block LDL^T factor preconditioned (the rest: Jacobi)
  double omega_max = 0;   ///< rad/s, bound on the largest frequency of the awake lattice
  int passes = 0;         ///< integrations of the step (> 1 when it woke sleepers and redid it)
  double max_strain = 0;  ///< largest |l / L - 1| of an awake vertex's springs at the step's end
  int stretch_redos = 0;  ///< integrations redone with more substeps because a spring overstretched
  int strain_limited = 0; ///< couple pairs the strain limit put back on its bound, all substeps and passes
  int sample_contacts = 0; ///< shell samples the colliders pushed out (set_colliders' samples), all substeps and passes
  SubstepCause substeps_by = SubstepCause::None;  ///< what set `substeps`
};

/// @brief Springs, forces and integration of an FfdLattice's control vertices.
class LatticeDynamics {
 public:
  /// @brief Dynamics of lattice (kept by reference; it must outlive this object). Masses start
  /// at 1 kg, areas at 0, nothing pinned, no wind. topology: its springs and couple neighbours;
  /// empty (the default) is the grid's, grid_topology(lattice.M()).
  LatticeDynamics(FfdLattice& lattice, const DynamicsParams& p, LatticeTopology topology = {});
  ~LatticeDynamics();
  LatticeDynamics(const LatticeDynamics&) = delete;
  LatticeDynamics& operator=(const LatticeDynamics&) = delete;

  /// @brief Replace the parameters; everything wakes if a parameter that moves vertices changed.
  void set_params(const DynamicsParams& p);
  /// @brief The parameters in force.
  const DynamicsParams& params() const { return p_; }
  /// @brief kg per control vertex (> 0); vertices whose mass changed wake, velocities are kept.
  void set_masses(const Eigen::VectorXd& m);
  /// @brief m^2 of sheet mapped to each control vertex (>= 0), for the wind pressure.
  void set_areas(const Eigen::VectorXd& a);
  /// @brief Per control vertex, in [0, 1]: the share of its springs' stiffness the material
  /// there keeps (1 intact, less where it burnt to ash). A spring takes the mean of its two ends;
  /// vertices whose strength changed wake.
  void set_strength(const Eigen::VectorXd& s);
  /// @brief Per control vertex: the stiffness share set by set_strength (1 at first).
  const Eigen::VectorXd& strength() const { return strength_; }
  /// @brief Per control vertex; pinned ones never move.
  void set_pinned(const std::vector<std::uint8_t>& pinned);
  const std::vector<std::uint8_t>& pinned() const { return pinned_; }
  /// @brief A curved shell's floor (null: every control vertex touches it at floor_z). A
  /// shell's couples need not reach its lowest points: a lantern's lowest couples sit above its
  /// rim, and which points are lowest changes as a sphere rolls (FloorSupport, contact.hpp).
  void set_floor_support(std::unique_ptr<FloorSupport> support);
  /// @brief Collision objects (docs/dynamics.md §3.2), kept by pointer (null: none): after every
  /// substep a free control vertex closer than margin (m, >= 0) to one is pushed out to margin
  /// along its normal, loses its inward normal speed relative to the collider and, by the
  /// collider's friction times that speed, its relative tangential speed; then so is each of
  /// samples (points of the shell carried by the control vertices; empty: none), by the
  /// least mass-weighted change of its vertices (shell_contact.hpp). A collider moved between
  /// steps moves at constant velocity over the next step (ColliderMotion). Everything wakes now
  /// and whenever colliders->version() changes.
  void set_colliders(std::shared_ptr<const Colliders> colliders, double margin, ContactSamples samples = {});
  /// @brief Wind velocity, m/s.
  void set_wind(const Eigen::Vector3d& w);
  /// @brief Wind velocity per control vertex ((2 M^2) x 3, m/s), used instead of set_wind's
  /// uniform wind on the lattice; 0 rows: back to the uniform wind.
  void set_wind_field(const RowMatX3& w);
  /// @brief Set positions and velocities ((2 M^2) x 3 each); everything wakes.
  void set_state(const RowMatX3& x, const RowMatX3& v);

  /// @brief Advance by dt. D: per couple total rotation so far (rad, eqs 4-6); the step
  /// turns its increase since the previous step into a crumple. heat: per control vertex,
  /// drives buoyancy. Throws std::runtime_error if an explicit integrator needs more than
  /// max_substeps substeps.
  StepStats step(double dt, const Eigen::VectorXd& D, const Eigen::VectorXd& heat);

  /// @brief What the set_* calls and a step change, besides the lattice's positions and what a
  /// step that throws restores itself: taken before a step that may throw, put back if it does.
  struct Checkpoint {
    Eigen::VectorXd mass, strength;
    Sleeping::State sleep;
    RowMatX3 vel, accel;
    Eigen::Vector3d wind;
    RowMatX3 grad_dir;
    Eigen::VectorXd grad_share;
    RowMatX3 hist_x, hist_v;
    std::vector<std::int64_t> hist_stamp;
    std::int64_t substep_count;
    double hist_h;
    Contacts::ColliderState colliders;  // the step's start sets the colliders' motion
  };
  Checkpoint checkpoint() const;
  void rollback(Checkpoint&& c);

  /// @brief Velocities ((2 M^2) x 3), m/s.
  const RowMatX3& velocities() const { return vel_; }
  /// @brief 1 where a vertex is awake (integrated by the next step), 0 where it sleeps or is
  /// pinned.
  std::vector<std::uint8_t> awake() const;
  /// @brief Total force per vertex at the current state (springs, gravity, damping, buoyancy
  /// from the last step's heat, wind); the crumple is a prescribed motion, not in it.
  RowMatX3 forces() const;
  /// @brief Exact Jacobian of the spring forces w.r.t. positions, (6 M^2) x (6 M^2).
  Eigen::SparseMatrix<double> stiffness_matrix() const;
  /// @brief Elastic energy of the springs, J.
  double energy() const;
  /// @brief Upper bound (block Gershgorin) on the largest frequency of M^-1 K over free
  /// vertices at the current state, rad/s.
  double max_frequency() const;
  /// @brief Rest lengths of the springs (changed by plasticity, or set from D when bimetal), m.
  const std::vector<double>& rest_lengths() const { return rest_len_; }
  /// @brief Spring endpoints, (springs) x 2.
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> spring_pairs() const;
  /// @brief Springs and couple neighbours.
  const LatticeTopology& topology() const { return topo_; }
  /// @brief Spring kind per spring: 0 structure, 1 shear, 2 flex, 3 thickness (top-bottom of a
  /// couple), 4 transverse (top-bottom diagonals between adjacent couples), 5 the zero-stiffness
  /// top-bottom diagonals that carry the membrane springs' blocks (membrane.hpp).
  const std::vector<std::uint8_t>& spring_kinds() const { return kind_; }
  /// @brief The lattice's own flexural rigidity, N m: h^2 / 2 (k_structure + k_shear +
  /// 4 k_flex) unit, h the couples' mean rest thickness (exact for pure bending of a grid).
  double lattice_rigidity() const;
  /// @brief The share of the lattice's own bending that its layer springs keep: B / lattice
  /// rigidity, at most 1 (1 when flexural_rigidity is 0).
  double bending_share() const { return bend_share_; }
  /// @brief Membrane springs between couples' centres (empty while bending_share() is 1).
  int membrane_springs() const { return membrane_ ? membrane_->size() : 0; }
  /// @brief Lattice corners whose diagonal has a knee (Membrane::add_corners): 4 on a grid.
  int membrane_corners() const { return membrane_ ? membrane_->corners() : 0; }

 private:
  void build_springs();
  void build_incidence();
  double spring_k(int s) const;
  double layer_k(int kind) const;
  double target_share() const;
  void add_membrane();
  void refresh_membrane();
  void refresh_spring_scale();
  double omega_bound(const std::vector<int>& verts) const;
  Eigen::Vector3d vertex_force(int v, const RowMatX3& x, const RowMatX3& vel) const;
  /// Speeds v's net force (less a floor's or collider's reaction) would give it within dt:
  /// free, nothing holding it back; held, its springs to its neighbours holding it (Sleeping).
  double free_speed(int v, double dt) const;
  double held_speed(int v, double dt) const;
  Eigen::Vector3d couple_normal(int v, const RowMatX3& x) const;
  int choose_substeps(double dt, double omega, double c_eff, SubstepCause* cause) const;
  int integrate(double dt, int substeps, StepStats& st);
  double max_active_strain() const;
  double max_damping_rate() const;
  void explicit_substep(double h, bool paper);
  int implicit_substep(double h);
  void implicit_assemble(double h);
  void implicit_rhs(double h);
  void apply_plasticity();
  void remove_crumple_translation();

  FfdLattice& lat_;
  DynamicsParams p_;
  LatticeTopology topo_;
  int C_, n_;  // couples, control vertices
  // Springs: endpoints, kind, rest length; per-vertex incidence (CSR, fixed order).
  std::vector<int> sa_, sb_;
  std::vector<std::uint8_t> kind_;
  std::vector<double> rest_len_;
  std::vector<double> spring_scale_;  // per spring: stiffness share kept (set_strength), 1 intact
  Eigen::VectorXd strength_;
  bool bimetal_all_ = true;           // the next bimetal step recomputes every spring
  SpringIncidence inc_;
  std::unique_ptr<Membrane> membrane_;  // null while the layers bend as the lattice's own
  double bend_share_ = 1.0;             // bending_share()
  std::vector<double> membrane_rest_save_;
  std::vector<int> vert_spring_;    // per couple: its top-bottom spring
  RowMatX3 vel_, drift_, disp_;
  RowMatX3 accel_;                  // last implicit acceleration per vertex: the CG warm start
  // BDF2's history: each vertex's state at the start of the substep it last took part in, that
  // substep's number and length. A vertex has history when that substep was the last one.
  RowMatX3 hist_x_, hist_v_;
  std::vector<std::int64_t> hist_stamp_;
  std::int64_t substep_count_ = 0;
  double hist_h_ = 0.0;
  void forget_history() { substep_count_ += 2; }  // no vertex's stamp matches any more
  double bdf2_ratio(double h) const;
  Eigen::VectorXd mass_, area_, heat_, heat_prev_, D_prev_, delta_;
  Eigen::Vector3d wind_{0, 0, 0};
  RowMatX3 wind_field_;             // per vertex (set_wind_field), 0 rows: wind_ everywhere
  std::vector<std::uint8_t> pinned_;
  RowMatX3 x_save_, v_save_;        // active vertices' state at the start of a pass
  Eigen::VectorXd heat_save_;        // restored, with rest_save_, when a step throws
  std::vector<double> rest_save_;
  std::unique_ptr<SelfContact> self_contact_;  // after each substep, as apply_colliders
  std::unique_ptr<StrainLimit> strain_limit_;  // after each substep, before the floor
  // The concerns split off, in this order (each views the members above and those before it).
  Bimetal bimetal_;                 // the curl's rest lengths
  Sleeping sleep_;                  // who is awake; the active set
  const std::vector<int>& active_ = sleep_.active();  // active vertices, in index order
  const std::vector<int>& slot_ = sleep_.slot();      // per vertex: position in active_ or -1
  Contacts contacts_;               // floor and colliders
  ImplicitSolver solver_;           // the implicit substeps' linear solve
};

}  // namespace thinburn
