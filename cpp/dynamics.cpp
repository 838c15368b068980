#include "dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "crumple.hpp"
#include "membrane.hpp"
#include "threads.hpp"

namespace thinburn {
namespace {

constexpr int kMaxPasses = 4;
constexpr int kMaxContactRounds = 8;  // solves per implicit substep while contacts are added
void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

// Amplification matrix of one substep h on the mode x'' = -w^2 x - c x'.
Eigen::Matrix2d amplification(Integrator integ, double h, double w, double c) {
  const double w2h = w * w * h;
  Eigen::Matrix2d G;
  if (integ == Integrator::Symplectic)
    G << 1.0 - w2h * h, h * (1.0 - c * h), -w2h, 1.0 - c * h;
  else  // the paper's scheme: x' = x + h v' + h^2 a / 2 = x + h v + 3/2 h^2 a
    G << 1.0 - 1.5 * w2h * h, h - 1.5 * c * h * h, -w2h, 1.0 - c * h;
  return G;
}

double spectral_radius(const Eigen::Matrix2d& G) {
  const double t = G.trace(), d = G.determinant();
  const double disc = t * t - 4.0 * d;
  if (disc >= 0.0) return 0.5 * (std::abs(t) + std::sqrt(disc));
  return std::sqrt(std::abs(d));
}

bool stable(Integrator integ, double h, double w, double c) {
  return spectral_radius(amplification(integ, h, w, c)) <= 1.0 + 1e-12 &&
         spectral_radius(amplification(integ, h, 0.0, c)) <= 1.0 + 1e-12;
}

}  // namespace

/// Largest h for which an explicit scheme is stable on every mode up to w with damping c.
double explicit_stability_limit(Integrator integ, double w, double c) {
  if (w <= 0.0 && c <= 0.0) return std::numeric_limits<double>::infinity();
  double lo = 0.0, hi = 1.0 / (w + c);
  while (stable(integ, hi, w, c)) {
    lo = hi;
    hi *= 2.0;
  }
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (stable(integ, mid, w, c) ? lo : hi) = mid;
  }
  return lo;
}

const std::vector<param::Field<DynamicsParams>>& DynamicsParams::fields() {
  using P = DynamicsParams;
  using namespace param;
  static const std::vector<Field<P>> table = {
      field("k_structure", &P::k_structure, at_least(0),
            "Table 1 coefficient of the axis-neighbour springs (per layer)"),
      field("k_shear", &P::k_shear, at_least(0), "Table 1 coefficient of the diagonal springs (per layer)"),
      field("k_flex", &P::k_flex, at_least(0), "Table 1 coefficient of the two-apart springs (per layer)"),
      field("k_thickness", &P::k_thickness, at_least(0), "coefficient of each couple's top-bottom spring"),
      field("k_transverse", &P::k_transverse, at_least(0),
            "coefficient of the top-bottom diagonals between adjacent couples"),
      field("stiffness_unit", &P::stiffness_unit, at_least(0),
            "N/m per unit coefficient: spring k = coefficient * unit"),
      field("flexural_rigidity", &P::flexural_rigidity, at_least(0),
            "N m: the sheet's bending rigidity (0: the lattice's own)"),
      field("c_damping", &P::c_damping, at_least(0), "1/s: eq 12 per kilogram, F = -c_damping m v"),
      field("gravity", &P::gravity, "m/s^2"),
      field("buoyancy", &P::buoyancy, "N/kg per unit heat, along +z"),
      field("wind_drag", &P::wind_drag, at_least(0), "Pa s/m: F = wind_drag area ((wind - v) . n) n"),
      field("has_floor", &P::has_floor, "nothing goes below floor_z"),
      field("floor_z", &P::floor_z, "m: the floor's height"),
      field("friction", &P::friction, at_least(0), "Coulomb coefficient on the floor"),
      field("slip_ratio", &P::slip_ratio, at_least(1),
            "implicit: a sticking floor contact whose hold asks more than slip_ratio x friction slides"),
      field("self_collision", &P::self_collision, "couples keep self_distance from the sheet's other layers"),
      field("self_distance", &P::self_distance, above(0),
            "lattice thicknesses a couple keeps from other parts of the sheet",
            "it counts lattice thicknesses"),
      field("contact_rounds", &P::contact_rounds, within(0, 16),
            "while layers touch, turns of strain limit, floor and self-contact after a substep's "
            "self-contact (0: self-contact once, last; docs/dynamics.md 3.4)"),
      field("strain_limit", &P::strain_limit, within(0, 1, false, true),
            "largest |l / L - 1| between neighbouring couples' centres (0: none)",
            "0 turns the limit off"),
      field("k_limit", &P::k_limit, at_least(0),
            "coefficient by which the membrane stiffens beyond 0.8 strain_limit (0: none)"),
      choice("integrator", &P::integrator, "Integrator", {"explicit", "symplectic", "implicit", "bdf2"},
             "the lattice's time integrator"),
      field("crumple_gain", &P::crumple_gain, "multiplies the increase of D turned into a crumple"),
      field("plasticity", &P::plasticity, within(0, 1), "share of each crumple the springs' rest lengths keep"),
      field("crumple_momentum", &P::crumple_momentum, "remove the crumple's net translation"),
      field("bimetal", &P::bimetal, "D shrinks the heated face's springs (false: Fig. 5's chord motion)"),
      field("anisotropic_curl", &P::anisotropic_curl, "bimetal: the curl bends across the front only"),
      field("sleep_speed", &P::sleep_speed, at_least(0), "m/s: slower vertices, unforced, may sleep"),
      field("sleeping", &P::sleeping, "false: every free vertex integrates every step"),
      field("wake_hold", &P::wake_hold, within(0, kMaxHold),
            "steps a flickering vertex stays awake (and, after a batch flickers, no batch sleeps)"),
      field("substeps", &P::substeps, within(0, kMaxFixedSubsteps), "substeps per step (0: chosen per step)",
            "every substep is run, so use 0 and let max_substeps cap them"),
      field("max_substeps", &P::max_substeps, within(1, kMaxSubstepsCeiling),
              "most substeps an explicit step may take (more throw)", "beyond that use the implicit integrator"),
      field("safety", &P::safety, within(0, 1, true), "explicit substep = safety * the stability limit"),
      field("max_stretch", &P::max_stretch, above(0), "implicit: largest relative change of a spring per substep"),
      field("cg_tolerance", &P::cg_tolerance, within(0, 1, true, true),
            "relative residual of the conjugate gradients"),
      field("cg_velocity_tolerance", &P::cg_velocity_tolerance, at_least(0),
            "m/s: absolute floor of the CG stopping test"),
      field("cg_max_iterations", &P::cg_max_iterations, at_least(1), "most conjugate-gradient iterations per solve"),
      choice("preconditioner", &P::preconditioner, "Preconditioner", {"auto", "ldlt", "jacobi"},
             "of the implicit solve's conjugate gradients"),
      field("ldlt_max_vertices", &P::ldlt_max_vertices, at_least(0), "auto: the largest awake set given ldlt"),
      field("refactor_iterations", &P::refactor_iterations, at_least(0),
              "ldlt: a solve taking more iterations refactors for the next one"),
  };
  return table;
}

void validate(const DynamicsParams& p) { param::check_all(DynamicsParams::fields(), p); }

void set_material(DynamicsParams& p, double k_structure, double k_shear, double k_flex, double c_damping) {
  // Table 1's names: the caller's material spells them so.
  const auto check = [](double v, const char* name, bool positive) {
    if (!std::isfinite(v) || v < 0.0 || (positive && v == 0.0))
      throw std::invalid_argument(std::string(name) + (positive ? " must be > 0" : " must be >= 0") +
                                  " and finite, got " + std::to_string(v));
  };
  check(k_structure, "K_structure", true);
  check(k_shear, "K_shear", false);
  check(k_flex, "K_flex", false);
  check(c_damping, "C_damping", false);
  p.k_structure = k_structure;
  p.k_shear = k_shear;
  p.k_flex = k_flex;
  p.c_damping = c_damping;
  p.k_transverse = k_structure;
  p.crumple_gain = kCrumpleReferenceK / k_structure;
}

LatticeDynamics::~LatticeDynamics() = default;

LatticeDynamics::LatticeDynamics(FfdLattice& lattice, const DynamicsParams& p, LatticeTopology topology)
    : lat_(lattice), p_(p), topo_(topology.couples > 0 ? std::move(topology) : grid_topology(lattice.M())),
      C_(lattice.couples()), n_(lattice.size()), bimetal_({topo_, lat_.rest(), sa_, sb_, rest_len_, p_}),
      sleep_(n_, inc_, pinned_, p_),
      contacts_(n_, {lat_, vel_, drift_, mass_, active_, slot_, inc_, kind_, rest_len_, p_}),
      solver_({active_, slot_, inc_, vert_spring_, mass_, contacts_, p_}) {
  validate(p);
  if (topo_.couples != C_ || static_cast<int>(topo_.nbr_offset.size()) != C_ + 1)
    throw std::invalid_argument("topology: " + std::to_string(topo_.couples) + " couples, the lattice has " +
                                std::to_string(C_));
  build_springs();
  vel_ = RowMatX3::Zero(n_, 3);
  accel_ = RowMatX3::Zero(n_, 3);
  hist_x_ = RowMatX3::Zero(n_, 3);
  hist_v_ = RowMatX3::Zero(n_, 3);
  hist_stamp_.assign(n_, -1);
  drift_ = RowMatX3::Zero(n_, 3);
  disp_ = RowMatX3::Zero(n_, 3);
  x_save_ = RowMatX3::Zero(n_, 3);
  v_save_ = RowMatX3::Zero(n_, 3);
  mass_ = Eigen::VectorXd::Ones(n_);
  strength_ = Eigen::VectorXd::Ones(n_);
  spring_scale_.assign(sa_.size(), 1.0);
  area_ = heat_ = heat_prev_ = Eigen::VectorXd::Zero(n_);
  D_prev_ = delta_ = Eigen::VectorXd::Zero(C_);
  pinned_.assign(n_, 0);
  self_contact_ = std::make_unique<SelfContact>(topo_, lat_.rest());
  strain_limit_ = std::make_unique<StrainLimit>(topo_, lat_.rest());
  bimetal_.build();
  bend_share_ = target_share();
  if (bend_share_ < 1.0) add_membrane();
}

void LatticeDynamics::build_springs() {
  const int ns0 = topo_.springs();
  sa_ = topo_.spring_a;
  sb_ = topo_.spring_b;
  kind_ = topo_.kind;
  rest_len_.resize(ns0);
  vert_spring_.assign(topo_.couples, 0);
  for (int s = 0; s < ns0; ++s) {
    if (sa_[s] < 0 || sa_[s] >= n_ || sb_[s] < 0 || sb_[s] >= n_ || sa_[s] == sb_[s])
      throw std::invalid_argument("topology: spring " + std::to_string(s) + " does not join two control vertices");
    rest_len_[s] = (lat_.rest().row(sb_[s]) - lat_.rest().row(sa_[s])).norm();
    if (kind_[s] == 3) vert_spring_[sa_[s] / 2] = s;
  }
  build_incidence();
}

void LatticeDynamics::build_incidence() {
  const int ns = static_cast<int>(sa_.size());
  inc_.start.assign(n_ + 1, 0);
  for (int s = 0; s < ns; ++s) {
    ++inc_.start[sa_[s] + 1];
    ++inc_.start[sb_[s] + 1];
  }
  for (int v = 0; v < n_; ++v) inc_.start[v + 1] += inc_.start[v];
  inc_.spring.assign(2 * ns, 0);
  inc_.other.assign(2 * ns, 0);
  std::vector<int> fill(inc_.start.begin(), inc_.start.end() - 1);
  for (int s = 0; s < ns; ++s) {
    inc_.spring[fill[sa_[s]]] = s;
    inc_.other[fill[sa_[s]]++] = sb_[s];
    inc_.spring[fill[sb_[s]]] = s;
    inc_.other[fill[sb_[s]]++] = sa_[s];
  }
  solver_.resize(sa_.size(), n_);
}

double LatticeDynamics::lattice_rigidity() const {
  double h = 0.0;
  for (int s : vert_spring_) h += rest_len_[s];
  h /= std::max(1, C_);
  return 0.5 * h * h * p_.stiffness_unit * (p_.k_structure + p_.k_shear + 4.0 * p_.k_flex);
}

double LatticeDynamics::target_share() const {
  if (!(p_.flexural_rigidity > 0.0)) return 1.0;
  const double own = lattice_rigidity();
  return own > 0.0 ? std::min(1.0, p_.flexural_rigidity / own) : 1.0;
}

void LatticeDynamics::add_membrane() {
  // Once built, the membrane stays (a share back at 1 gives its springs zero stiffness).
  membrane_ = std::make_unique<Membrane>(sa_, sb_, kind_);
  const RowMatX3& r = lat_.rest();
  for (const auto& [a, b] : membrane_->missing_diagonals(sa_, sb_)) {
    sa_.push_back(a);
    sb_.push_back(b);
    kind_.push_back(kPatternSpring);
    const double len = (r.row(b) - r.row(a)).norm();
    rest_len_.push_back(len);
  }
  bimetal_.add_springs();
  membrane_->link(sa_, sb_, r, C_);
  membrane_->add_corners(topo_.grid_side);
  build_incidence();  // the solver's pattern gained blocks
  refresh_spring_scale();
  sleep_.wake_all();
}

void LatticeDynamics::refresh_membrane() {
  // Each pair of layer springs keeps bend_share_ of its stiffness; its membrane spring takes
  // 2 (1 - share) k, so that the pair stretches as before (membrane.hpp). The flex pairs'
  // membrane part joins the structure springs': under a uniform stretch a flex spring two
  // spacings long stores what a structure spring of 4 k_flex does (exact on a grid's interior).
  if (!membrane_) return;
  // The knee (the yarns, straight) follows the strength as the rest does: ash holds little.
  std::vector<double>& k = membrane_->stiffness();
  std::vector<double>& knee = membrane_->knee_stiffness();
  for (int e = 0; e < membrane_->size(); ++e) {
    const int t = membrane_->top(e), b = membrane_->bottom(e);
    const double layer = kind_[t] == 0 ? layer_k(0) + 4.0 * layer_k(2) : layer_k(kind_[t]);
    const double scale = 0.5 * (spring_scale_[t] + spring_scale_[b]);
    k[e] = 2.0 * (1.0 - bend_share_) * layer * scale;
    knee[e] = p_.k_limit * p_.stiffness_unit * scale;
  }
  membrane_->set_knee(kKneeShare * p_.strain_limit);
}

double LatticeDynamics::layer_k(int kind) const {
  const double c[6] = {p_.k_structure, p_.k_shear, p_.k_flex, p_.k_thickness, p_.k_transverse, 0.0};
  return c[kind] * p_.stiffness_unit;
}

double LatticeDynamics::spring_k(int s) const {
  const double share = membrane_ && membrane_->carried(s) ? bend_share_ : 1.0;
  return layer_k(kind_[s]) * share * spring_scale_[s];
}

void LatticeDynamics::set_strength(const Eigen::VectorXd& s) {
  require(s.size() == n_, "strength must have 2*M*M = " + std::to_string(n_) + " entries, got " +
                              std::to_string(s.size()));
  for (int v = 0; v < n_; ++v)
    require(std::isfinite(s(v)) && s(v) >= 0.0 && s(v) <= 1.0,
            "strength must be in [0, 1] (entry " + std::to_string(v) + ")");
  for (int v = 0; v < n_; ++v)
    if (s(v) != strength_(v)) sleep_.wake(v);
  strength_ = s;
  refresh_spring_scale();
}

void LatticeDynamics::refresh_spring_scale() {
  // A spring keeps the mean strength of its two ends; the membrane springs follow theirs.
  spring_scale_.resize(sa_.size());
  for (std::size_t q = 0; q < sa_.size(); ++q) spring_scale_[q] = 0.5 * (strength_(sa_[q]) + strength_(sb_[q]));
  refresh_membrane();
}

void LatticeDynamics::set_params(const DynamicsParams& p) {
  validate(p);
  const DynamicsParams& o = p_;
  const bool moved =
      o.k_structure != p.k_structure || o.k_shear != p.k_shear || o.k_flex != p.k_flex ||
      o.k_thickness != p.k_thickness || o.k_transverse != p.k_transverse ||
      o.stiffness_unit != p.stiffness_unit ||
      o.c_damping != p.c_damping || o.gravity != p.gravity || o.buoyancy != p.buoyancy ||
      o.wind_drag != p.wind_drag || o.has_floor != p.has_floor || o.floor_z != p.floor_z ||
      o.friction != p.friction || o.integrator != p.integrator || o.sleeping != p.sleeping ||
      o.sleep_speed != p.sleep_speed || o.bimetal != p.bimetal || o.flexural_rigidity != p.flexural_rigidity ||
      o.strain_limit != p.strain_limit || o.k_limit != p.k_limit ||
      (p.bimetal && o.crumple_gain != p.crumple_gain);
  if (o.integrator != p.integrator) forget_history();
  if (p.bimetal && (!o.bimetal || o.crumple_gain != p.crumple_gain || o.anisotropic_curl != p.anisotropic_curl)) bimetal_all_ = true;
  p_ = p;
  bend_share_ = target_share();
  if (bend_share_ < 1.0 && !membrane_) add_membrane();
  refresh_membrane();
  if (moved) sleep_.wake_all();
}

LatticeDynamics::Checkpoint LatticeDynamics::checkpoint() const {
  return Checkpoint{mass_, strength_, sleep_.state(), vel_, accel_, wind_, bimetal_.grad_dir(), bimetal_.grad_share(),
                    hist_x_, hist_v_, hist_stamp_, substep_count_, hist_h_, contacts_.collider_state()};
}

void LatticeDynamics::rollback(Checkpoint&& c) {
  mass_ = std::move(c.mass);
  strength_ = std::move(c.strength);
  sleep_.restore(std::move(c.sleep));
  vel_ = std::move(c.vel);
  accel_ = std::move(c.accel);
  bimetal_.restore(std::move(c.grad_dir), std::move(c.grad_share));
  wind_ = c.wind;
  hist_x_ = std::move(c.hist_x);
  hist_v_ = std::move(c.hist_v);
  hist_stamp_ = std::move(c.hist_stamp);
  substep_count_ = c.substep_count;
  hist_h_ = c.hist_h;
  contacts_.restore(std::move(c.colliders));
  refresh_spring_scale();  // also covers a membrane added since the checkpoint
}

void LatticeDynamics::set_masses(const Eigen::VectorXd& m) {
  require(m.size() == n_, "masses must have 2*M*M = " + std::to_string(n_) + " entries, got " +
                              std::to_string(m.size()));
  for (int v = 0; v < n_; ++v)
    require(std::isfinite(m(v)) && m(v) > 0.0, "masses must be finite and > 0 (entry " +
                                                    std::to_string(v) + ")");
  for (int v = 0; v < n_; ++v)
    if (m(v) != mass_(v)) sleep_.wake(v);
  mass_ = m;
}

void LatticeDynamics::set_areas(const Eigen::VectorXd& a) {
  require(a.size() == n_, "areas must have 2*M*M = " + std::to_string(n_) + " entries, got " +
                              std::to_string(a.size()));
  for (int v = 0; v < n_; ++v)
    require(std::isfinite(a(v)) && a(v) >= 0.0, "areas must be finite and >= 0 (entry " +
                                                     std::to_string(v) + ")");
  for (int v = 0; v < n_; ++v)
    if (a(v) != area_(v)) sleep_.wake(v);
  area_ = a;
}

void LatticeDynamics::set_pinned(const std::vector<std::uint8_t>& pinned) {
  require(int(pinned.size()) == n_, "pinned must have 2*M*M = " + std::to_string(n_) +
                                        " entries, got " + std::to_string(pinned.size()));
  for (int v = 0; v < n_; ++v) {
    pinned_[v] = pinned[v] ? 1 : 0;
    if (pinned_[v]) vel_.row(v).setZero();
  }
  forget_history();
  sleep_.wake_all();
}

void LatticeDynamics::set_floor_support(std::unique_ptr<FloorSupport> support) {
  contacts_.set_floor_support(std::move(support));
  sleep_.wake_all();
}

void LatticeDynamics::set_wind(const Eigen::Vector3d& w) {
  require(w.allFinite(), "wind must be finite");
  if (w == wind_) return;
  wind_ = w;
  for (int v = 0; v < n_; ++v)
    if (area_(v) > 0.0) sleep_.wake(v);
}

void LatticeDynamics::set_wind_field(const RowMatX3& w) {
  require(w.rows() == 0 || w.rows() == n_, "wind field: one wind per control vertex expected");
  require(w.allFinite(), "wind field must be finite");
  wind_field_ = w;
  for (int v = 0; v < n_; ++v)
    if (area_(v) > 0.0) sleep_.wake(v);
}

void LatticeDynamics::set_state(const RowMatX3& x, const RowMatX3& v) {
  require(x.rows() == n_ && x.allFinite(), "positions must be finite, 2*M*M x 3");
  require(v.rows() == n_ && v.allFinite(), "velocities must be finite, 2*M*M x 3");
  lat_.positions() = x;
  vel_ = v;
  accel_.setZero();
  forget_history();
  self_contact_->reset();
  for (int q = 0; q < n_; ++q)
    if (pinned_[q]) vel_.row(q).setZero();
  sleep_.wake_all();
}

Eigen::Vector3d LatticeDynamics::couple_normal(int v, const RowMatX3& x) const {
  const int c = v / 2;
  const Eigen::Vector3d d = (x.row(2 * c + 1) - x.row(2 * c)).transpose();
  const double l = d.norm();
  return l > 1e-300 ? Eigen::Vector3d(d / l) : Eigen::Vector3d::UnitZ();
}

Eigen::Vector3d LatticeDynamics::vertex_force(int v, const RowMatX3& x, const RowMatX3& vel) const {
  const double m = mass_(v);
  Eigen::Vector3d f = m * p_.gravity - p_.c_damping * m * vel.row(v).transpose();
  f.z() += m * p_.buoyancy * heat_(v);
  for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
    const int s = inc_.spring[q];
    const Eigen::Vector3d d = (x.row(inc_.other[q]) - x.row(v)).transpose();
    const double l = d.norm();
    if (l > 1e-300) f += spring_k(s) * (l - rest_len_[s]) / l * d;
  }
  if (membrane_) f += membrane_->force(v, x);
  if (p_.wind_drag > 0.0 && area_(v) > 0.0) {
    const Eigen::Vector3d n = couple_normal(v, x);
    const Eigen::Vector3d wind = wind_field_.rows() ? Eigen::Vector3d(wind_field_.row(v).transpose()) : wind_;
    f += p_.wind_drag * area_(v) * (wind - vel.row(v).transpose()).dot(n) * n;
  }
  return f;
}

double LatticeDynamics::free_speed(int v, double dt) const {
  return contacts_.supported(v, vertex_force(v, lat_.positions(), vel_)).norm() / mass_(v) * dt;
}

double LatticeDynamics::held_speed(int v, double dt) const {
  // A sleeper whose springs tie it to anchors moves as backward Euler on it alone says, the
  // anchors fixed: (m/dt + dt K) u = f, K the Hessian block of its springs to them (geometric
  // part clamped, so positive semidefinite). An anchor is pinned, or a sleeper resting on the
  // floor or a collider whose static friction could take all of f on top of its own load.
  // Along a stiff spring that speed is the quasi-static f / (k dt), not the free f dt / m:
  // an awake neighbour's drift stresses the top layer of a paper sheet lying on a table by k
  // times a few nanometres, a force that would move it by those nanometres. Springs to other
  // sleepers count for nothing: held by them, each of a row of sleepers would lag by its own
  // bit and the lags add up along the row, and a sleeper that holds a force passes none of it
  // on (a strip drooping over a table's edge would not pull the part lying on it).
  const RowMatX3& x = lat_.positions();
  const Eigen::Vector3d f = contacts_.supported(v, vertex_force(v, x, vel_));
  const double m = mass_(v), load = f.norm();
  Eigen::Matrix3d K = Eigen::Matrix3d::Zero();
  for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
    const int o = inc_.other[q], s = inc_.spring[q];
    const bool anchor = pinned_[o] || (!sleep_.awake()[o] &&
                                       contacts_.friction_reserve(o, vertex_force(o, x, vel_)) >= load);
    if (anchor) K += spring_block((x.row(o) - x.row(v)).transpose(), spring_k(s), rest_len_[s], true);
  }
  const Eigen::Matrix3d A = (m / dt) * Eigen::Matrix3d::Identity() + dt * K;
  return A.llt().solve(f).norm();
}

std::vector<std::uint8_t> LatticeDynamics::awake() const {
  std::vector<std::uint8_t> out(n_);
  for (int v = 0; v < n_; ++v) out[v] = sleep_.awake()[v] && !pinned_[v];
  return out;
}

RowMatX3 LatticeDynamics::forces() const {
  RowMatX3 f(n_, 3);
  for (int v = 0; v < n_; ++v) f.row(v) = vertex_force(v, lat_.positions(), vel_).transpose();
  return f;
}

double LatticeDynamics::energy() const {
  const RowMatX3& x = lat_.positions();
  double e = 0.0;
  for (std::size_t s = 0; s < sa_.size(); ++s) {
    const double dl = (x.row(sb_[s]) - x.row(sa_[s])).norm() - rest_len_[s];
    e += 0.5 * spring_k(int(s)) * dl * dl;
  }
  return membrane_ ? e + membrane_->energy(x) : e;
}

Eigen::SparseMatrix<double> LatticeDynamics::stiffness_matrix() const {
  const RowMatX3& x = lat_.positions();
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(sa_.size() * 36);
  if (membrane_) membrane_->blocks(x, {}, false);
  for (std::size_t s = 0; s < sa_.size(); ++s) {
    const int a = sa_[s], b = sb_[s];
    Eigen::Matrix3d J = spring_block((x.row(b) - x.row(a)).transpose(), spring_k(int(s)), rest_len_[s], false);
    if (membrane_) J += membrane_->share(int(s));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        t.emplace_back(3 * a + r, 3 * a + c, -J(r, c));
        t.emplace_back(3 * b + r, 3 * b + c, -J(r, c));
        t.emplace_back(3 * a + r, 3 * b + c, J(r, c));
        t.emplace_back(3 * b + r, 3 * a + c, J(r, c));
      }
  }
  Eigen::SparseMatrix<double> K(3 * n_, 3 * n_);
  K.setFromTriplets(t.begin(), t.end());
  return K;
}

Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> LatticeDynamics::spring_pairs() const {
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> out(sa_.size(), 2);
  for (std::size_t s = 0; s < sa_.size(); ++s) out.row(s) << sa_[s], sb_[s];
  return out;
}

double LatticeDynamics::omega_bound(const std::vector<int>& verts) const {
  const RowMatX3& x = lat_.positions();
  double worst = 0.0;
  for (int v : verts) {
    if (pinned_[v]) continue;
    double b = 0.0;
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
      const int s = inc_.spring[q], o = inc_.other[q];
      const double l = (x.row(o) - x.row(v)).norm();
      const double g = l > 1e-300 ? std::abs(1.0 - rest_len_[s] / l) : 1.0;
      const double norm = spring_k(s) * std::max(1.0, g);
      b += norm * (1.0 / mass_(v) + 1.0 / std::sqrt(mass_(v) * mass_(o)));
    }
    if (membrane_) b += membrane_->row_bound(v, x, mass_);
    worst = std::max(worst, b);
  }
  return std::sqrt(worst);
}

double LatticeDynamics::max_frequency() const {
  std::vector<int> all(n_);
  for (int v = 0; v < n_; ++v) all[v] = v;
  return omega_bound(all);
}

double LatticeDynamics::max_damping_rate() const {
  double c = p_.c_damping;
  for (int v : active_) c = std::max(c, p_.c_damping + p_.wind_drag * area_(v) / mass_(v));
  return c;
}

void LatticeDynamics::apply_plasticity() {
  const RowMatX3& x = lat_.positions();
  const int ns = static_cast<int>(sa_.size());
  parallel_for(0, ns, kRowCost, [&](long s_) {
    const int s = static_cast<int>(s_);
    const int a = sa_[s], b = sb_[s];
    if (disp_.row(a).squaredNorm() == 0.0 && disp_.row(b).squaredNorm() == 0.0) return;
    const double before = (x.row(b) - x.row(a)).norm();
    const double after = (x.row(b) + disp_.row(b) - x.row(a) - disp_.row(a)).norm();
    rest_len_[s] = std::max(0.0, rest_len_[s] + p_.plasticity * (after - before));
  });
  if (!membrane_) return;
  std::vector<double>& rest = membrane_->rest();
  for (int e = 0; e < membrane_->size(); ++e) {
    const int ca = membrane_->couple_a(e), cb = membrane_->couple_b(e);
    const Eigen::Vector3d d = couple_centre(x, cb) - couple_centre(x, ca);
    const Eigen::Vector3d dd = couple_centre(disp_, cb) - couple_centre(disp_, ca);
    if (dd.squaredNorm() == 0.0) continue;
    rest[e] = std::max(0.0, rest[e] + p_.plasticity * ((d + dd).norm() - d.norm()));
  }
}

double LatticeDynamics::max_active_strain() const {
  const RowMatX3& x = lat_.positions();
  double worst = 0.0;
  for (int v : active_)
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
      const int s = inc_.spring[q], o = inc_.other[q];
      // A layer spring whose membrane part a membrane spring carries also bends: its strain
      // is the curvature's (kappa h / 2), and the membrane spring's is the sheet's stretch.
      if (rest_len_[s] <= 0.0 || kind_[s] == kPatternSpring || (membrane_ && membrane_->carried(s))) continue;
      worst = std::max(worst, std::abs((x.row(o) - x.row(v)).norm() / rest_len_[s] - 1.0));
    }
  return membrane_ ? std::max(worst, membrane_->max_strain(x, slot_)) : worst;
}

int LatticeDynamics::integrate(double dt, int substeps, StepStats& st) {
  // The implicit integrator takes one Newton step per substep: springs far from rest break
  // the linearisation, and a frame-sized step from rest can fling a pinned cloth beyond its
  // own reach. A step that ends with a spring stretched or squashed by more than
  // kStretchRedo of its rest length (and by kGrowth times more than at its start) is redone from the
  // pass's start with more substeps, up to max_substeps, while more substeps still change the
  // answer: once a redo leaves the worst strain within kConverged of the try before, the
  // strain is the motion's own (a soft silk), not the step's.
  constexpr double kStretchRedo = 0.01, kGrowth = 1.5, kConverged = 0.8;
  constexpr int kMaxRedos = 6;
  const bool implicit = is_implicit(p_.integrator);
  const double before = implicit ? max_active_strain() : 0.0;
  double last = std::numeric_limits<double>::infinity();
  for (;;) {
    const double h = substeps > 0 ? dt / substeps : 0.0;
    for (int k = 0; k < substeps; ++k) {
      contacts_.begin_substep(h);
      if (implicit)
        st.cg_iterations += implicit_substep(h);
      else
        explicit_substep(h, p_.integrator == Integrator::Explicit);
      if (p_.strain_limit > 0.0)
        st.strain_limited += strain_limit_->apply(p_.strain_limit, lat_.positions(), vel_, mass_, slot_);
      contacts_.apply_floor(h);
      st.sample_contacts += contacts_.apply_colliders(h);
      if (p_.self_collision) {
        const double sep = self_contact_->separation(p_.self_distance);
        int touching = self_contact_->apply(sep, lat_.positions(), vel_, mass_, slot_);
        // Self-contact comes last and pushed a pile's couples past the strain limit (cells'
        // sides 8.7 % short in the Blender pile, the surface 4.5 % at p99): while layers
        // touch, the limit, the floor and the contacts take turns (docs/dynamics.md §3.4).
        // Nothing touches in the demo scenes, which stay bit for bit as they were.
        for (int round = 0; round < p_.contact_rounds && touching > 0 && p_.strain_limit > 0.0; ++round) {
          if (strain_limit_->apply(p_.strain_limit, lat_.positions(), vel_, mass_, slot_) == 0) break;
          contacts_.apply_floor(h);
          touching = self_contact_->apply(sep, lat_.positions(), vel_, mass_, slot_);
        }
      }
    }
    st.max_strain = max_active_strain();
    if (!implicit || p_.substeps > 0 || substeps == 0 ||
        substeps >= p_.max_substeps || st.max_strain <= std::max(kStretchRedo, kGrowth * before) ||
        st.max_strain > kConverged * last || st.stretch_redos >= kMaxRedos)
      return substeps;
    last = st.max_strain;
    for (int a = 0; a < st.awake; ++a) {
      lat_.positions().row(active_[a]) = x_save_.row(a);
      vel_.row(active_[a]) = v_save_.row(a);
    }
    forget_history();  // the history was the failed try's: the redo starts with backward Euler
    ++st.stretch_redos;
    st.substeps_by = SubstepCause::StretchRedo;
    const double grow = std::ceil(st.max_strain / kStretchRedo);
    substeps = static_cast<int>(std::min<double>(p_.max_substeps, substeps * std::max(2.0, grow)));
  }
}

const char* substep_cause_name(SubstepCause c) {
  switch (c) {
    case SubstepCause::None: return "none";
    case SubstepCause::Set: return "set";
    case SubstepCause::One: return "one";
    case SubstepCause::Stability: return "stability";
    case SubstepCause::Accuracy: return "accuracy";
    case SubstepCause::Contact: return "contact";
    case SubstepCause::StretchRedo: return "stretch_redo";
  }
  return "none";
}

namespace {
// The larger of a rule's need and the contacts', and which one it was (One when neither
// asks for more than a substep).
int larger_need(double rule, SubstepCause rule_cause, int contact, SubstepCause* cause) {
  if (contact > 1 && contact >= rule) {
    *cause = SubstepCause::Contact;
    return contact;
  }
  *cause = rule > 1.0 ? rule_cause : SubstepCause::One;
  return static_cast<int>(std::max(1.0, rule));
}
}  // namespace

int LatticeDynamics::choose_substeps(double dt, double omega, double c_eff, SubstepCause* cause) const {
  if (p_.substeps > 0) {
    *cause = SubstepCause::Set;
    return p_.substeps;
  }
  if (!is_implicit(p_.integrator)) {
    const double h = p_.safety * explicit_stability_limit(p_.integrator, omega, c_eff);
    const double need = std::ceil(dt / h);
    if (!(need <= p_.max_substeps))
      throw std::runtime_error(
          std::string(p_.integrator == Integrator::Explicit ? "Explicit" : "Symplectic") +
          " integration of dt = " + std::to_string(dt) + " s needs " + std::to_string(need) +
          " substeps (largest frequency " + std::to_string(omega) + " rad/s, stable substep " +
          std::to_string(h) + " s), more than max_substeps = " + std::to_string(p_.max_substeps) +
          "; use the Implicit integrator or raise max_substeps");
    return larger_need(need, SubstepCause::Stability, contacts_.contact_substeps(dt), cause);
  }
  // Implicit: one Newton step per substep is accurate while no spring changes length by more
  // than max_stretch of its rest length in a substep.
  const RowMatX3& x = lat_.positions();
  double ratio = 0.0;
  for (int v : active_)
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
      const int s = inc_.spring[q], o = inc_.other[q];
      if (kind_[s] == kPatternSpring) continue;
      const double len = std::max(rest_len_[s], 1e-3 * (x.row(o) - x.row(v)).norm());
      if (len <= 0.0) continue;
      const double rel = (vel_.row(v) + drift_.row(v) - vel_.row(o) - drift_.row(o)).norm();
      ratio = std::max(ratio, rel * dt / (p_.max_stretch * len));
    }
  const double accuracy = std::min(std::ceil(ratio), double(p_.max_substeps));
  return larger_need(accuracy, SubstepCause::Accuracy, contacts_.contact_substeps(dt), cause);
}

void LatticeDynamics::explicit_substep(double h, bool paper) {
  const ImplicitSolver::Buffers B = solver_.buffers();
  RowMatX3& x = lat_.positions();
  const int na = static_cast<int>(active_.size());
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    vec3(B.f, a) = vertex_force(v, x, vel_) / mass_(v);
  });
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    const Eigen::Vector3d acc = vec3(B.f, a);
    vel_.row(v) += h * acc.transpose();
    contacts_.press(v);  // before the move: a resting vertex must not slide h^2 a_t first
    x.row(v) += h * (vel_.row(v) + drift_.row(v));
    if (paper) x.row(v) += 0.5 * h * h * acc.transpose();
  });
}

void LatticeDynamics::implicit_assemble(double h) {
  const ImplicitSolver::Buffers B = solver_.buffers();
  const RowMatX3& x = lat_.positions();
  const int na = static_cast<int>(active_.size());
  const double h2 = h * h;
  // Jacobian blocks (clamped to positive semidefinite) of springs touching active vertices;
  // each spring is computed by its smallest-index active endpoint, with the membrane springs'
  // shares of its block (membrane.hpp).
  if (membrane_) membrane_->blocks(x, slot_, true);
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
      const int s = inc_.spring[q], o = inc_.other[q];
      if (slot_[o] >= 0 && o < v) continue;
      const Eigen::Vector3d d = (x.row(o) - x.row(v)).transpose();
      Eigen::Matrix3d J = spring_block(d, spring_k(s), rest_len_[s], true);
      if (membrane_) J += membrane_->share(s);
      store_sym(B.jac + 6 * s, J);
    }
  });
  // Floor contact: a vertex on the floor that would move into it keeps v_z = 0 in this substep
  // (a filtered DOF of the conjugate gradients); implicit_substep adds the vertices that the
  // solution takes below the floor. Forces and the diagonal blocks of
  // A = M (1 + h c) + h W + h^2 J; every contact is decided before any right-hand side reads
  // a neighbour's drift (substep_drift).
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    const Eigen::Vector3d f = vertex_force(v, x, vel_);
    vec3(B.f, a) = f;
    contacts_.decide(v, h, f);
    Eigen::Matrix3d D = mass_(v) * (1.0 + h * p_.c_damping) * Eigen::Matrix3d::Identity();
    if (p_.wind_drag > 0.0 && area_(v) > 0.0) {
      const Eigen::Vector3d n = couple_normal(v, x);
      D += h * p_.wind_drag * area_(v) * n * n.transpose();
    }
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q)
      D += h2 * load_sym(B.jac + 6 * inc_.spring[q]);
    mat3(B.diag, a) = D;
  });
  implicit_rhs(h);
}

void LatticeDynamics::implicit_rhs(double h) {
  // b = h (f + h K w), w = v + substep drift: K w is the force change along the motion.
  const ImplicitSolver::Buffers B = solver_.buffers();
  const int na = static_cast<int>(active_.size());
  // Each active vertex's w once, not once per spring that reads it; a vertex that does not
  // move has no contact, so its drift is the crumple's alone.
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    vec3(B.w, a) = vel_.row(v).transpose() + contacts_.substep_drift(v, h);
  });
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    const Eigen::Vector3d wv = vec3(B.w, a);
    Eigen::Vector3d Kw = Eigen::Vector3d::Zero();
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
      const int o = inc_.other[q], so = slot_[o];
      const Eigen::Vector3d wo =
          so >= 0 ? Eigen::Vector3d(vec3(B.w, so)) : Eigen::Vector3d(vel_.row(o).transpose() + drift_.row(o).transpose());
      Kw -= load_sym(B.jac + 6 * inc_.spring[q]) * (wv - wo);
    }
    // Unfiltered: the solve filters its residual, and a contact's row of b is what
    // constraint_impulse weighs the floor's impulse against.
    vec3(B.b, a) = h * (vec3(B.f, a) + h * Kw) + contacts_.friction_impulse(v);
  });
}

double LatticeDynamics::bdf2_ratio(double h) const {
  // BDF2 needs every active vertex's state one substep back; a vertex that just woke (or a
  // redone step) has none, and the substep is backward Euler (ratio 0) for all.
  if (p_.integrator != Integrator::Bdf2 || !(hist_h_ > 0.0)) return 0.0;
  for (int v : active_)
    if (hist_stamp_[v] != substep_count_) return 0.0;
  return h / hist_h_;
}

int LatticeDynamics::implicit_substep(double h_step) {
  RowMatX3& x = lat_.positions();
  const int na = static_cast<int>(active_.size());
  // Variable-step BDF2 (Choi and Ko 2002 use it for cloth) is backward Euler from an
  // extrapolated state: with r = h / h_prev, x_new = x^ + h^ v_new, v_new = v^ + h^ a(x_new, v_new),
  // where x^ = ((1 + r)^2 x - r^2 x_prev) / (1 + 2r) (v^ alike) and h^ = h (1 + r) / (1 + 2r).
  // r = 0 is backward Euler itself. Second order: the curl and the wind's push converge as dt^2
  // where backward Euler's artificial damping (h w^2 / 2 on a mode of frequency w) lags them as dt.
  const double r = bdf2_ratio(h_step);
  const double h = h_step * (1.0 + r) / (1.0 + 2.0 * r);
  const double c_now = (1.0 + r) * (1.0 + r) / (1.0 + 2.0 * r), c_prev = r * r / (1.0 + 2.0 * r);
  if (p_.integrator == Integrator::Bdf2) {  // backward Euler keeps no history
    for (int a = 0; a < na; ++a) {
      const int v = active_[a];
      const Eigen::RowVector3d xv = x.row(v), vv = vel_.row(v);
      // A vertex on the floor starts from its own state (a backward-Euler substep of h^): a
      // multistep method's history does not carry across the floor's impulses. Extrapolated,
      // a contact's height was extrapolated off the floor from its landing, the contact test
      // then found it free, and it slid without static friction: the demo's A4 in 3 m/s wind
      // went 0.47 m in 20 s at dt = 1/24 s, 47 times the reference's motion (RMS error 46.6;
      // keeping only the height unextrapolated gave 0.027, keeping the whole state 0.008).
      const bool on_floor = p_.has_floor && xv(2) <= contacts_.floor_at(v);
      if (r > 0.0 && !on_floor) {
        x.row(v) = c_now * xv - c_prev * hist_x_.row(v);
        vel_.row(v) = c_now * vv - c_prev * hist_v_.row(v);
      }
      hist_x_.row(v) = xv;
      hist_v_.row(v) = vv;
      hist_stamp_[v] = substep_count_ + 1;
    }
    ++substep_count_;
    hist_h_ = h_step;
  }
  implicit_assemble(h);
  const ImplicitSolver::Buffers B = solver_.buffers();
  // Warm start from the previous substep's acceleration (a smooth motion changes it little);
  // constrained DOFs start at their prescribed value.
  for (int a = 0; a < na; ++a) {
    const int v = active_[a];
    Eigen::Vector3d d0 = h * accel_.row(v).transpose();
    for (int i = 0; i < 3; ++i)
      if (contacts_.filtered(v, i)) d0(i) = -vel_(v, i);
    vec3(B.dv, a) = d0;
  }
  int iterations = solver_.solve(h);
  // Contacts the floor would have to pull let go, and holds beyond friction slide (before the
  // landings, which change dv); vertices the solution takes below the floor become contacts;
  // then the system is solved again from the last solution (each round changes at least one
  // contact).
  const auto impulse = [&](int a) { return solver_.constraint_impulse(h, a); };
  for (int round = 1; round < kMaxContactRounds; ++round) {
    const bool revised = contacts_.revise_contacts(h, impulse);
    const bool landed = contacts_.add_landings(h, B.dv);
    if (!landed && !revised) break;
    implicit_rhs(h);
    iterations += solver_.solve(h);
  }
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    const Eigen::Vector3d u = contacts_.substep_drift(v, h);  // before x changes: it reads x
    vel_.row(v) += vec3(B.dv, a).transpose();
    accel_.row(v) = vec3(B.dv, a).transpose() / h;
    x.row(v) += h * (vel_.row(v) + u.transpose());
    contacts_.settle(v, h);
  });
  return iterations;
}

void LatticeDynamics::remove_crumple_translation() {
  // Fig. 5 turns neighbours about a fixed line, which moves the sheet's centre of mass; an
  // internal stress cannot. Taking the mass-weighted mean out of the displaced vertices keeps
  // the bend and drops the drift (which otherwise walks a burning sheet across the table).
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  double m = 0.0;
  for (int v = 0; v < n_; ++v)
    if (!pinned_[v] && disp_.row(v).squaredNorm() > 0.0) {
      p += mass_(v) * disp_.row(v).transpose();
      m += mass_(v);
    }
  if (!(m > 0.0)) return;
  const Eigen::RowVector3d mean = (p / m).transpose();
  for (int v = 0; v < n_; ++v)
    if (!pinned_[v] && disp_.row(v).squaredNorm() > 0.0) disp_.row(v) -= mean;
}

void LatticeDynamics::set_colliders(std::shared_ptr<const Colliders> colliders, double margin,
                                    ContactSamples samples) {
  require(std::isfinite(margin) && margin >= 0.0,
          "collider margin must be finite and >= 0 m, got " + std::to_string(margin));
  for (std::size_t i = 0; i < samples.vertex.size(); ++i)
    require(samples.vertex[i] >= 0 && samples.vertex[i] < n_, "collider samples: vertex index out of range");
  contacts_.set_colliders(std::move(colliders), margin, std::move(samples));
  sleep_.wake_all();
}

StepStats LatticeDynamics::step(double dt, const Eigen::VectorXd& D, const Eigen::VectorXd& heat) {
  require(std::isfinite(dt) && dt > 0.0, "dt must be finite and > 0, got " + std::to_string(dt));
  require(D.size() == C_, "D must have one entry per couple (" + std::to_string(C_) + "), got " +
                                   std::to_string(D.size()));
  require(heat.size() == n_, "heat must have 2*M*M = " + std::to_string(n_) + " entries, got " +
                                 std::to_string(heat.size()));
  require(D.allFinite(), "D must be finite");
  require(heat.allFinite(), "heat must be finite");
  StepStats st;
  solver_.reset_count();
  heat_save_ = heat_;
  heat_ = heat;
  delta_ = p_.crumple_gain * (D - D_prev_);
  const bool crumple = delta_.size() > 0 && delta_.cwiseAbs().maxCoeff() > 0.0;
  const bool bimetal = p_.bimetal && (crumple || bimetal_all_);
  if (crumple && !p_.bimetal) {
    if (topo_.grid_side > 0)
      crumple_displacements(topo_.grid_side, lat_.positions(), delta_, pinned_, disp_);
    else
      crumple_displacements(topo_.nbr_offset, topo_.nbr_index, lat_.positions(), delta_, pinned_, disp_);
    if (p_.crumple_momentum) remove_crumple_translation();
  } else {
    disp_.setZero();
  }
  std::vector<std::uint8_t>& forced = sleep_.forced();
  for (int v = 0; v < n_; ++v)
    forced[v] = disp_.row(v).squaredNorm() > 0.0 || (p_.bimetal && delta_(v / 2) != 0.0) ||
                std::abs(p_.buoyancy * (heat_(v) - heat_prev_(v))) * dt >= p_.sleep_speed;
  if (bimetal && bimetal_all_) sleep_.wake_all();
  if (contacts_.colliders_moved(dt)) sleep_.wake_all();
  if (!p_.sleeping)
    sleep_.wake_all();
  else
    sleep_.wake_around_forcing(vel_);
  drift_ = disp_ / dt;
  const bool plastic = crumple && !p_.bimetal && p_.plasticity > 0.0;
  if (plastic || bimetal) {
    rest_save_ = rest_len_;
    if (membrane_) membrane_rest_save_ = membrane_->rest();
  }
  if (bimetal) bimetal_.apply(D, delta_, bimetal_all_, membrane_.get());
  // What would set a vertex moving: its force less what a floor or a collider it rests on takes.
  const Sleeping::Speed free = [this, dt](int v) { return free_speed(v, dt); };
  const Sleeping::Speed held = [this, dt](int v) { return held_speed(v, dt); };
  bool plastic_done = false;
  try {
    for (int pass = 1;; ++pass) {
      sleep_.collect_active();
      st.passes = pass;
      st.awake = static_cast<int>(active_.size());
      st.omega_max = omega_bound(active_);
      st.substeps_by = SubstepCause::None;
      st.substeps = active_.empty() ? 0 : choose_substeps(dt, st.omega_max, max_damping_rate(), &st.substeps_by);
      if (!plastic_done && plastic) apply_plasticity();
      plastic_done = true;
      for (int a = 0; a < st.awake; ++a) {
        x_save_.row(a) = lat_.positions().row(active_[a]);
        v_save_.row(a) = vel_.row(active_[a]);
      }
      st.substeps = integrate(dt, st.substeps, st);
      if (!p_.sleeping || pass >= kMaxPasses) break;
      // Redo the step with the sleepers its motion stressed awake, unless they are few next to
      // the awake set: those join the next step (a step late) rather than cost a whole pass.
      const int woke = sleep_.wake_stressed_sleepers(held);
      if (woke == 0 || woke * kRedoShare < st.awake) break;
      for (int a = 0; a < st.awake; ++a) {
        lat_.positions().row(active_[a]) = x_save_.row(a);
        vel_.row(active_[a]) = v_save_.row(a);
      }
      forget_history();
    }
  } catch (...) {
    heat_ = heat_save_;
    if (plastic || bimetal) {
      rest_len_ = rest_save_;
      if (membrane_) membrane_->rest() = membrane_rest_save_;
    }
    throw;
  }
  if (bimetal) bimetal_all_ = false;
  st.factorizations = solver_.factorizations();
  st.ldlt_solves = solver_.ldlt_solves();
  D_prev_ = D;
  if (p_.sleeping) sleep_.update_sleep(vel_, accel_, free);
  sleep_.end_step();
  for (int v = 0; v < n_; ++v)
    if (sleep_.awake()[v]) heat_prev_(v) = heat_(v);
  return st;
}

}  // namespace thinburn
