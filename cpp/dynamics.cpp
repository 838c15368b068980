#include "dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "block_ldlt.hpp"
#include "crumple.hpp"
#include "membrane.hpp"
#include "threads.hpp"

namespace thinburn {
namespace {

constexpr int kDotChunk = 4096;
// Work per item, in kParallelWork's units (threads.hpp): a vertex's or a spring's row of
// forces, Jacobian or CG product is about 32; one entry of an axpy about 11. So a loop over
// fewer than about 1000 vertices, or an axpy over fewer than 3000 entries, stays on one thread.
constexpr long kRowCost = 32;
constexpr long kAxpyCost = 11;
constexpr int kMaxPasses = 4;
constexpr int kRedoShare = 16;   // a step is redone when it stresses awake over 1/16 of its awake count
constexpr int kSleepShare = 10;  // vertices fall asleep only when over 1/10 of the awake set is quiet
constexpr int kMaxHold = 10000;  // steps: the longest flicker hold (and wake_hold's upper bound)
constexpr int kMaxContactRounds = 8;  // solves per implicit substep while contacts are added
constexpr double kPi = 3.14159265358979323846;
// A couple whose D changes by this much across its spacing curls across the front only.
constexpr double kAnisotropicTurn = 0.25;

Eigen::Vector3d couple_centre(const RowMatX3& x, int c) {
  return 0.5 * (x.row(2 * c) + x.row(2 * c + 1)).transpose();
}

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
      field("self_collision", &P::self_collision, "couples keep self_distance from the sheet's other layers"),
      field("self_distance", &P::self_distance, above(0),
            "lattice thicknesses a couple keeps from other parts of the sheet",
            "it counts lattice thicknesses"),
      field("strain_limit", &P::strain_limit, within(0, 1, false, true),
            "largest |l / L - 1| between neighbouring couples' centres where the sheet is intact (0: none)",
            "0 turns the limit off"),
      choice("integrator", &P::integrator, "Integrator", {"explicit", "symplectic", "implicit", "bdf2"},
             "the lattice's time integrator"),
      field("crumple_gain", &P::crumple_gain, "multiplies the increase of D turned into a crumple"),
      field("plasticity", &P::plasticity, within(0, 1), "share of each crumple the springs' rest lengths keep"),
      field("crumple_momentum", &P::crumple_momentum, "remove the crumple's net translation"),
      field("bimetal", &P::bimetal, "D shrinks the heated face's springs (false: Fig. 5's chord motion)"),
      field("anisotropic_curl", &P::anisotropic_curl, "bimetal: the curl bends across the front only"),
      field("sleep_speed", &P::sleep_speed, at_least(0), "m/s: slower vertices, unforced, may sleep"),
      field("sleeping", &P::sleeping, "false: every free vertex integrates every step"),
      field("wake_hold", &P::wake_hold, within(0, kMaxHold), "steps a flickering vertex stays awake"),
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

// The implicit system over the active vertices, lower triangle of 3x3 blocks by columns, and its
// sparse block LDL^T factorization (block_ldlt.hpp), the conjugate gradients' preconditioner.
// The pattern depends only on the active set: values are refilled in the order the pattern was
// built, and the symbolic analysis (AMD ordering, elimination tree) is redone only when the
// active set changes. The numeric factorization is kept over substeps and steps (masses,
// lengths and contacts change slowly), and over changes of the active set, until a solve needs
// more than refactor_iterations iterations or the active set has moved too far from the
// factored one.
struct LatticeDynamics::Factor {
  std::vector<int> active;      // the active set the pattern was built for
  std::vector<int> slot;        // per vertex: its position in `active`, -1 if not in it
  std::vector<int> blk_start;   // per active vertex: its column's 3x3 blocks in blk_row/blk_spring
  std::vector<int> blk_row;     // row slot of each block; the vertex itself (diagonal) first
  std::vector<int> blk_spring;  // the spring of an off-diagonal block, -1 on the diagonal
  std::vector<std::pair<int, int>> sort_buf;
  std::vector<double> values;   // 9 per block of blk_row, column-major
  BlockLdlt ldlt;
  Eigen::VectorXd rhs;
  bool analysed = false;  // ldlt holds the symbolic analysis of `active`
  bool valid = false;     // ldlt holds a numeric factorization of `active`'s system
  bool stale = false;     // the last solve took too many iterations: refactor before the next
};

LatticeDynamics::~LatticeDynamics() = default;

LatticeDynamics::LatticeDynamics(FfdLattice& lattice, const DynamicsParams& p, LatticeTopology topology)
    : lat_(lattice), p_(p), topo_(topology.couples > 0 ? std::move(topology) : grid_topology(lattice.M())),
      C_(lattice.couples()), n_(lattice.size()) {
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
  awake_.assign(n_, 1);
  forced_.assign(n_, 0);
  hold_.assign(n_, 0);
  hold_len_.assign(n_, 0);
  slept_at_.assign(n_, std::numeric_limits<std::int64_t>::min() / 2);
  mark_.assign(n_, 0);
  list_.reserve(n_);
  slot_.assign(n_, -1);
  active_.reserve(n_);
  contact_ = Eigen::VectorXd::Constant(n_, -1.0);
  stick_.assign(n_, 0);
  factor_ = std::make_unique<Factor>();
  self_contact_ = std::make_unique<SelfContact>(topo_, lat_.rest());
  strain_limit_ = std::make_unique<StrainLimit>(topo_, lat_.rest());
  build_bimetal();
  bend_share_ = target_share();
  if (bend_share_ < 1.0) add_membrane();
}

void LatticeDynamics::build_bimetal() {
  // Geometry of the rest lattice that the bimetal rest lengths bend: each spring joins two
  // couples whose centres are mid_sep_ apart, at offsets +-(half the couple's thickness) from the
  // mid-surface (+ toward the top).
  const RowMatX3& r = lat_.rest();
  const int C = topo_.couples;
  base_len_ = rest_len_;
  mid_sep_.clear();
  off_a_.clear();
  off_b_.clear();
  add_spring_geometry();
  grad_dir_ = RowMatX3::Zero(C, 3);
  grad_share_ = Eigen::VectorXd::Zero(C);
  changed_.assign(C, 0);
  couple_spacing_ = Eigen::VectorXd::Zero(C);
  for (int c = 0; c < C; ++c) {
    double sum = 0.0;
    int k = 0;
    for (int q = topo_.nbr_offset[c]; q < topo_.nbr_offset[c + 1]; ++q, ++k)
      sum += (couple_centre(r, topo_.nbr_index[q]) - couple_centre(r, c)).norm();
    couple_spacing_(c) = k > 0 ? sum / k : 1.0;
  }
}

void LatticeDynamics::add_spring_geometry() {
  // mid_sep_, off_a_, off_b_ of the springs from the first not yet measured to the last.
  const RowMatX3& r = lat_.rest();
  auto offset = [&](int v) {
    const double half = 0.5 * (r.row(v | 1) - r.row(v & ~1)).norm();
    return (v & 1) ? half : -half;
  };
  for (std::size_t s = mid_sep_.size(); s < sa_.size(); ++s) {
    mid_sep_.push_back((couple_centre(r, sb_[s] / 2) - couple_centre(r, sa_[s] / 2)).norm());
    off_a_.push_back(offset(sa_[s]));
    off_b_.push_back(offset(sb_[s]));
  }
}

static double chord_ratio(double kappa, double sep) {
  // Chord over arc of a mid-surface bent to curvature kappa over arc length sep, as
  // bimetal_ratio's with both offsets 0 (and its half-turn clamp).
  if (!(sep > 0.0)) return 1.0;
  const double half = 0.5 * std::clamp(kappa, -kPi / sep, kPi / sep) * sep;
  return std::abs(half) > 1e-12 ? std::sin(half) / half : 1.0;
}

double LatticeDynamics::bimetal_ratio(int s, double kappa) const {
  // Distance between two points of a sheet bent to curvature kappa (centre of curvature on the
  // top side), at mid-surface arc length s apart and offsets oa, ob along the normals:
  // d^2 = (oa - ob)^2 + (1 - kappa oa)(1 - kappa ob) chord^2, chord = 2 sin(kappa s / 2) / kappa.
  // The top face (o > 0) shortens by kappa o per unit length, the bottom lengthens: a bimetal
  // strip. Returned relative to the flat sheet, so that the rest lattice's own shape is kept.
  const double sep = mid_sep_[s], oa = off_a_[s], ob = off_b_[s];
  const double d0 = std::sqrt((oa - ob) * (oa - ob) + sep * sep);
  if (!(d0 > 0.0) || sep == 0.0) return 1.0;
  // At most a half turn between the couples, and the layers stay on their side of the centre.
  const double omax = std::max(std::abs(oa), std::abs(ob));
  double k = std::clamp(kappa, -kPi / sep, kPi / sep);
  if (omax > 0.0) k = std::clamp(k, -0.9 / omax, 0.9 / omax);
  const double half = 0.5 * k * sep;
  const double chord = std::abs(half) > 1e-12 ? sep * std::sin(half) / half : sep;
  const double d2 = (oa - ob) * (oa - ob) + (1.0 - k * oa) * (1.0 - k * ob) * chord * chord;
  return std::sqrt(std::max(d2, 0.0)) / d0;
}

void LatticeDynamics::apply_bimetal(const Eigen::VectorXd& D, bool all) {
  // Rest lengths are a function of D alone (not of the path), so the springs never carry the
  // history of earlier crumples; only springs near a couple whose D changed are recomputed.
  //
  // The curl bends across the fire's front, not equally every way: a heated face shrinking
  // alike in all directions wants a dome, which a sheet cannot take without stretching, so
  // paper rolls about lines along the burning edge instead. A spring along unit direction u
  // takes the curvature times (u . g)^2, g the direction in which D grows (a couple's D
  // gradient); where D is flat across a couple (|grad D| spacing << kAnisotropicTurn) the
  // factor blends to 1/2, the mean over directions.
  const int C = topo_.couples;
  const RowMatX3& r = lat_.rest();
  auto centre = [&](int c) { return couple_centre(r, c); };
  for (int c = 0; c < C; ++c) {
    bool near = all || delta_(c) != 0.0;
    for (int q = topo_.nbr_offset[c]; q < topo_.nbr_offset[c + 1] && !near; ++q) near = delta_(topo_.nbr_index[q]) != 0.0;
    changed_[c] = near;
    if (!near) continue;
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int q = topo_.nbr_offset[c]; q < topo_.nbr_offset[c + 1]; ++q) {
      const int o = topo_.nbr_index[q];
      const Eigen::Vector3d e = centre(o) - centre(c);
      const double l2 = e.squaredNorm();
      if (l2 > 0) g += (D(o) - D(c)) * e / l2;
    }
    const double k = topo_.nbr_offset[c + 1] - topo_.nbr_offset[c];
    const double slope = k > 0 ? 2.0 * g.norm() / k : 0.0;  // |grad D| (rad/m), averaged over axes
    grad_share_(c) = std::min(1.0, slope * couple_spacing_(c) / kAnisotropicTurn);
    grad_dir_.row(c) = g.norm() > 0 ? Eigen::RowVector3d(g.normalized().transpose()) : Eigen::RowVector3d::Zero();
  }
  auto factor = [&](int c, const Eigen::Vector3d& u) {
    const double along = u.dot(grad_dir_.row(c).transpose());
    return grad_share_(c) * along * along + (1.0 - grad_share_(c)) * 0.5;
  };
  // The curvature between two couples: their mean D over spacing, along the front.
  auto curvature = [&](int ca, int cb) {
    Eigen::Vector3d u = centre(cb) - centre(ca);
    u = u.norm() > 0 ? Eigen::Vector3d(u.normalized()) : u;
    const double f = p_.anisotropic_curl ? 0.5 * (factor(ca, u) + factor(cb, u)) : 1.0;
    return 0.5 * p_.crumple_gain * f * (D(ca) / couple_spacing_(ca) + D(cb) / couple_spacing_(cb));
  };
  const int ns = static_cast<int>(sa_.size());
  parallel_for(0, ns, kRowCost, [&](long s_) {
    const int s = static_cast<int>(s_);
    const int ca = sa_[s] / 2, cb = sb_[s] / 2;
    if (ca == cb) return;  // a couple's own thickness spring keeps its length
    if (!changed_[ca] && !changed_[cb]) return;
    rest_len_[s] = base_len_[s] * bimetal_ratio(s, curvature(ca, cb));
  });
  if (!membrane_) return;
  // A membrane spring lies on the mid-surface: bent, its ends are a chord of the arc apart.
  std::vector<double>& rest = membrane_->rest();
  parallel_for(0, membrane_->size(), kRowCost, [&](long e_) {
    const int e = static_cast<int>(e_);
    const int ca = membrane_->couple_a(e), cb = membrane_->couple_b(e);
    if (!changed_[ca] && !changed_[cb]) return;
    rest[e] = membrane_->base()[e] * chord_ratio(curvature(ca, cb), membrane_->base()[e]);
  });
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
  inc_start_.assign(n_ + 1, 0);
  for (int s = 0; s < ns; ++s) {
    ++inc_start_[sa_[s] + 1];
    ++inc_start_[sb_[s] + 1];
  }
  for (int v = 0; v < n_; ++v) inc_start_[v + 1] += inc_start_[v];
  inc_spring_.assign(2 * ns, 0);
  inc_other_.assign(2 * ns, 0);
  std::vector<int> fill(inc_start_.begin(), inc_start_.end() - 1);
  for (int s = 0; s < ns; ++s) {
    inc_spring_[fill[sa_[s]]] = s;
    inc_other_[fill[sa_[s]]++] = sb_[s];
    inc_spring_[fill[sb_[s]]] = s;
    inc_other_[fill[sb_[s]]++] = sa_[s];
  }
  // Buffers of the solver: 6 per spring (Jacobian blocks), 27 per vertex (diagonal block and
  // the two blocks of its row of the couple-block preconditioner),
  // 3 per vertex for each of the CG vectors and the forces, and the dot-product partials.
  work_.assign(6 * std::size_t(ns) + 27 * std::size_t(n_) + 7 * 3 * std::size_t(n_) +
                   (3 * std::size_t(n_)) / kDotChunk + 2,
               0.0);
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
    base_len_.push_back(len);
  }
  add_spring_geometry();
  membrane_->link(sa_, sb_, r, C_);
  build_incidence();
  factor_ = std::make_unique<Factor>();  // the pattern gained blocks
  refresh_spring_scale();
  std::fill(awake_.begin(), awake_.end(), 1);
}

void LatticeDynamics::refresh_membrane() {
  // Each pair of layer springs keeps bend_share_ of its stiffness; its membrane spring takes
  // 2 (1 - share) k, so that the pair stretches as before (membrane.hpp). The flex pairs'
  // membrane part joins the structure springs': under a uniform stretch a flex spring two
  // spacings long stores what a structure spring of 4 k_flex does (exact on a grid's interior).
  if (!membrane_) return;
  std::vector<double>& k = membrane_->stiffness();
  for (int e = 0; e < membrane_->size(); ++e) {
    const int t = membrane_->top(e), b = membrane_->bottom(e);
    const double layer = kind_[t] == 0 ? layer_k(0) + 4.0 * layer_k(2) : layer_k(kind_[t]);
    k[e] = 2.0 * (1.0 - bend_share_) * layer * 0.5 * (spring_scale_[t] + spring_scale_[b]);
  }
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
    if (s(v) != strength_(v)) awake_[v] = 1;
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
      o.strain_limit != p.strain_limit ||
      (p.bimetal && o.crumple_gain != p.crumple_gain);
  if (o.integrator != p.integrator) forget_history();
  if (p.bimetal && (!o.bimetal || o.crumple_gain != p.crumple_gain || o.anisotropic_curl != p.anisotropic_curl)) bimetal_all_ = true;
  p_ = p;
  bend_share_ = target_share();
  if (bend_share_ < 1.0 && !membrane_) add_membrane();
  refresh_membrane();
  if (moved) std::fill(awake_.begin(), awake_.end(), 1);
}

LatticeDynamics::Checkpoint LatticeDynamics::checkpoint() const {
  return Checkpoint{mass_, strength_, awake_, hold_, hold_len_, vel_, accel_, wind_, grad_dir_, grad_share_,
                    hist_x_, hist_v_, hist_stamp_, substep_count_, hist_h_};
}

void LatticeDynamics::rollback(Checkpoint&& c) {
  mass_ = std::move(c.mass);
  strength_ = std::move(c.strength);
  awake_ = std::move(c.awake);
  hold_ = std::move(c.hold);
  hold_len_ = std::move(c.hold_len);
  vel_ = std::move(c.vel);
  accel_ = std::move(c.accel);
  grad_dir_ = std::move(c.grad_dir);
  grad_share_ = std::move(c.grad_share);
  wind_ = c.wind;
  hist_x_ = std::move(c.hist_x);
  hist_v_ = std::move(c.hist_v);
  hist_stamp_ = std::move(c.hist_stamp);
  substep_count_ = c.substep_count;
  hist_h_ = c.hist_h;
  refresh_spring_scale();  // also covers a membrane added since the checkpoint
}

void LatticeDynamics::set_masses(const Eigen::VectorXd& m) {
  require(m.size() == n_, "masses must have 2*M*M = " + std::to_string(n_) + " entries, got " +
                              std::to_string(m.size()));
  for (int v = 0; v < n_; ++v)
    require(std::isfinite(m(v)) && m(v) > 0.0, "masses must be finite and > 0 (entry " +
                                                    std::to_string(v) + ")");
  for (int v = 0; v < n_; ++v)
    if (m(v) != mass_(v)) awake_[v] = 1;
  mass_ = m;
}

void LatticeDynamics::set_areas(const Eigen::VectorXd& a) {
  require(a.size() == n_, "areas must have 2*M*M = " + std::to_string(n_) + " entries, got " +
                              std::to_string(a.size()));
  for (int v = 0; v < n_; ++v)
    require(std::isfinite(a(v)) && a(v) >= 0.0, "areas must be finite and >= 0 (entry " +
                                                     std::to_string(v) + ")");
  for (int v = 0; v < n_; ++v)
    if (a(v) != area_(v)) awake_[v] = 1;
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
  std::fill(awake_.begin(), awake_.end(), 1);
}

void LatticeDynamics::set_floor_offsets(const Eigen::VectorXd& offsets) {
  require(offsets.size() == 0 || offsets.size() == n_, "floor offsets: one per control vertex expected");
  require(offsets.allFinite(), "floor offsets must be finite");
  floor_offset_ = offsets;
  std::fill(awake_.begin(), awake_.end(), 1);
}

void LatticeDynamics::set_wind(const Eigen::Vector3d& w) {
  require(w.allFinite(), "wind must be finite");
  if (w == wind_) return;
  wind_ = w;
  for (int v = 0; v < n_; ++v)
    if (area_(v) > 0.0) awake_[v] = 1;
}

void LatticeDynamics::set_wind_field(const RowMatX3& w) {
  require(w.rows() == 0 || w.rows() == n_, "wind field: one wind per control vertex expected");
  require(w.allFinite(), "wind field must be finite");
  wind_field_ = w;
  for (int v = 0; v < n_; ++v)
    if (area_(v) > 0.0) awake_[v] = 1;
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
  std::fill(awake_.begin(), awake_.end(), 1);
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
  for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
    const int s = inc_spring_[q];
    const Eigen::Vector3d d = (x.row(inc_other_[q]) - x.row(v)).transpose();
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

std::vector<std::uint8_t> LatticeDynamics::awake() const {
  std::vector<std::uint8_t> out(n_);
  for (int v = 0; v < n_; ++v) out[v] = awake_[v] && !pinned_[v];
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
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
      const int s = inc_spring_[q], o = inc_other_[q];
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

// ---------------------------------------------------------------------------------------------
// Work buffers: [jacobian blocks 6/spring | diagonal blocks 9/vertex | preconditioner 18/vertex |
// f, b, dv, r, z, p, Ap: 3/vertex each | dot partials].
namespace {
struct Buffers {
  double *jac, *diag, *pinv, *f, *b, *dv, *r, *z, *p, *Ap, *partial;
};
Buffers buffers(std::vector<double>& w, std::size_t ns, std::size_t n) {
  Buffers B;
  double* q = w.data();
  B.jac = q;
  q += 6 * ns;
  B.diag = q;
  q += 9 * n;
  B.pinv = q;
  q += 18 * n;
  double** vecs[7] = {&B.f, &B.b, &B.dv, &B.r, &B.z, &B.p, &B.Ap};
  for (double** v : vecs) {
    *v = q;
    q += 3 * n;
  }
  B.partial = q;
  return B;
}

// Sum of a[i] * b[i] in fixed chunks summed in order: the same bits for any thread count.
double det_dot(const double* a, const double* b, int len, double* partial) {
  const int chunks = (len + kDotChunk - 1) / kDotChunk;
  parallel_for(0, chunks, kDotChunk, [&](long c_) {
    const int c = static_cast<int>(c_);
    double s = 0.0;
    const int end = std::min(len, (c + 1) * kDotChunk);
    for (int i = c * kDotChunk; i < end; ++i) s += a[i] * b[i];
    partial[c] = s;
  });
  double t = 0.0;
  for (int c = 0; c < chunks; ++c) t += partial[c];
  return t;
}

void store_sym(double* out, const Eigen::Matrix3d& J) {
  out[0] = J(0, 0), out[1] = J(1, 1), out[2] = J(2, 2);
  out[3] = J(0, 1), out[4] = J(0, 2), out[5] = J(1, 2);
}
Eigen::Matrix3d load_sym(const double* s) {
  Eigen::Matrix3d J;
  J << s[0], s[3], s[4], s[3], s[1], s[5], s[4], s[5], s[2];
  return J;
}
Eigen::Map<Eigen::Vector3d> vec3(double* base, int slot) {
  return Eigen::Map<Eigen::Vector3d>(base + 3 * slot);
}
Eigen::Map<Eigen::Matrix3d> mat3(double* base, int slot) {
  return Eigen::Map<Eigen::Matrix3d>(base + 9 * slot);
}
}  // namespace

Eigen::Vector3d LatticeDynamics::supported(int v, Eigen::Vector3d f) const {
  if (p_.has_floor && lat_.positions()(v, 2) <= floor_at(v) && f.z() < 0.0) {
    const double normal = -f.z();
    f.z() = 0.0;
    const double t = std::hypot(f.x(), f.y());
    const double keep = t > p_.friction * normal ? (t - p_.friction * normal) / t : 0.0;
    f.x() *= keep;
    f.y() *= keep;
  }
  // A collider holds a vertex resting on it the same way: the inward push is taken, and static
  // friction takes up to friction times that of the tangential force.
  ColliderHit hit;
  if (collider_contact(lat_.positions().row(v).transpose(), hit)) {
    const double fn = f.dot(hit.normal);
    if (fn < 0.0) {
      const Eigen::Vector3d ft = f - fn * hit.normal;
      const double t = ft.norm();
      const double keep = t > hit.friction * -fn ? (t - hit.friction * -fn) / t : 0.0;
      f = keep * ft;
    }
  }
  return f;
}

void LatticeDynamics::collect_active() {
  active_.clear();
  std::fill(slot_.begin(), slot_.end(), -1);
  for (int v = 0; v < n_; ++v)
    if (awake_[v] && !pinned_[v]) {
      slot_[v] = static_cast<int>(active_.size());
      active_.push_back(v);
    }
}

void LatticeDynamics::wake_rings(std::vector<std::uint8_t>& flag, int rings) const {
  // flag: 1 = seed; grows by spring neighbours `rings` times (2 marks the new ring).
  for (int r = 0; r < rings; ++r) {
    for (int v = 0; v < n_; ++v)
      if (flag[v] == 1)
        for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q)
          if (!flag[inc_other_[q]]) flag[inc_other_[q]] = 2;
    for (auto& f : flag)
      if (f == 2) f = 1;
  }
}

void LatticeDynamics::wake_around_forcing() {
  // Forced vertices (a crumple, or a heat change that would reach sleep_speed within the step)
  // wake with two rings of spring neighbours; moving ones with one ring.
  std::vector<std::uint8_t>& seed = mark_;
  for (int v = 0; v < n_; ++v) seed[v] = forced_[v];
  wake_rings(seed, 1);
  for (int v = 0; v < n_; ++v)
    if (awake_[v] && vel_.row(v).norm() >= p_.sleep_speed) seed[v] = 1;
  wake_rings(seed, 1);
  for (int v = 0; v < n_; ++v) {
    if (seed[v]) awake_[v] = 1;
    seed[v] = 0;
  }
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
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
      const int s = inc_spring_[q], o = inc_other_[q];
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
      if (implicit)
        st.cg_iterations += implicit_substep(h);
      else
        explicit_substep(h, p_.integrator == Integrator::Explicit);
      if (p_.strain_limit > 0.0)
        st.strain_limited += strain_limit_->apply(p_.strain_limit, lat_.positions(), vel_, mass_, slot_);
      apply_floor(h);
      apply_colliders(h);
      if (p_.self_collision)
        self_contact_->apply(self_contact_->separation(p_.self_distance), lat_.positions(), vel_, mass_, slot_);
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
    const double grow = std::ceil(st.max_strain / kStretchRedo);
    substeps = static_cast<int>(std::min<double>(p_.max_substeps, substeps * std::max(2.0, grow)));
  }
}

int LatticeDynamics::choose_substeps(double dt, double omega, double c_eff) const {
  if (p_.substeps > 0) return p_.substeps;
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
    return std::max({1, static_cast<int>(need), contact_substeps(dt)});
  }
  // Implicit: one Newton step per substep is accurate while no spring changes length by more
  // than max_stretch of its rest length in a substep.
  const RowMatX3& x = lat_.positions();
  double ratio = 0.0;
  for (int v : active_)
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
      const int s = inc_spring_[q], o = inc_other_[q];
      if (kind_[s] == kPatternSpring) continue;
      const double len = std::max(rest_len_[s], 1e-3 * (x.row(o) - x.row(v)).norm());
      if (len <= 0.0) continue;
      const double rel = (vel_.row(v) + drift_.row(v) - vel_.row(o) - drift_.row(o)).norm();
      ratio = std::max(ratio, rel * dt / (p_.max_stretch * len));
    }
  const double need = std::max(std::ceil(ratio), double(contact_substeps(dt)));
  return static_cast<int>(std::clamp(need, 1.0, double(p_.max_substeps)));
}

void LatticeDynamics::explicit_substep(double h, bool paper) {
  Buffers B = buffers(work_, sa_.size(), n_);
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
    // A vertex resting on the floor that the substep presses into it: the floor takes the
    // normal speed and friction the tangential one before the position moves. Applied after
    // the move (apply_floor alone), each substep let a resting vertex slide h^2 a_t first, and
    // a sheet that a light wind pushed crept across its table by T h a_t (the demo's A4 in
    // 3 m/s wind: 9 mm in 20 s at h = 1/6000 s).
    if (p_.has_floor && x(v, 2) <= floor_at(v) && vel_(v, 2) <= 0.0) {
      const double removed = -vel_(v, 2), t = std::hypot(vel_(v, 0), vel_(v, 1));
      const double keep = t > p_.friction * removed ? (t - p_.friction * removed) / t : 0.0;
      vel_(v, 0) *= keep;
      vel_(v, 1) *= keep;
      vel_(v, 2) = 0.0;
    }
    x.row(v) += h * (vel_.row(v) + drift_.row(v));
    if (paper) x.row(v) += 0.5 * h * h * acc.transpose();
  });
}

void LatticeDynamics::implicit_assemble(double h) {
  Buffers B = buffers(work_, sa_.size(), n_);
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
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
      const int s = inc_spring_[q], o = inc_other_[q];
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
    contact_(v) = -1.0;
    stick_[v] = 0;
    if (p_.has_floor && x(v, 2) <= floor_at(v)) {
      const double vz_free = vel_(v, 2) + h * f.z() / mass_(v);
      if (vz_free <= 0.0) {
        contact_(v) = -vz_free;
        // Static friction inside the solve: a contact whose tangential speed at the substep's
        // end (explicit guess) the floor's friction impulse (friction x the normal speed it
        // removes) can absorb sticks, all three velocity components filtered to zero. Applied
        // after the solve instead, friction stopped such a vertex only once its neighbours had
        // been solved as if it slid, and a sheet a light wind pushed crept across its table
        // by an amount proportional to the substep (the demo's A4 in 3 m/s wind: 0.39 m in
        // 20 s at dt = 1/24 s, against 7 mm with the symplectic integrator's small substeps).
        const double tx = vel_(v, 0) + h * f.x() / mass_(v), ty = vel_(v, 1) + h * f.y() / mass_(v);
        // A contact that Fig. 5's prescribed crumple moves this step follows it (the chord's
        // in-plane part is what lets its neighbours lift): it slides, as before.
        stick_[v] = p_.friction > 0.0 && drift_.row(v).squaredNorm() == 0.0 &&
                    std::hypot(tx, ty) <= p_.friction * contact_(v);
      }
    }
    Eigen::Matrix3d D = mass_(v) * (1.0 + h * p_.c_damping) * Eigen::Matrix3d::Identity();
    if (p_.wind_drag > 0.0 && area_(v) > 0.0) {
      const Eigen::Vector3d n = couple_normal(v, x);
      D += h * p_.wind_drag * area_(v) * n * n.transpose();
    }
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q)
      D += h2 * load_sym(B.jac + 6 * inc_spring_[q]);
    mat3(B.diag, a) = D;
  });
  implicit_rhs(h);
}

void LatticeDynamics::build_jacobi(double h) {
  Buffers B = buffers(work_, sa_.size(), n_);
  const int na = static_cast<int>(active_.size());
  const double h2 = h * h;
  // Couple-block Jacobi: the top-bottom spring is the stiffest, so both vertices of a couple are
  // inverted together (6 x 6); a vertex whose partner is not active gets its 3 x 3 inverse.
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a], pa = slot_[v ^ 1];
    if (pa < 0) {
      mat3(B.pinv, 2 * a) = mat3(B.diag, a).inverse();
      mat3(B.pinv, 2 * a + 1).setZero();
      return;
    }
    Eigen::Matrix<double, 6, 6> C;
    const Eigen::Matrix3d J = load_sym(B.jac + 6 * vert_spring_[v / 2]);
    C.topLeftCorner<3, 3>() = mat3(B.diag, a);
    C.bottomRightCorner<3, 3>() = mat3(B.diag, pa);
    C.topRightCorner<3, 3>() = -h2 * J;
    C.bottomLeftCorner<3, 3>() = -h2 * J;
    const Eigen::Matrix<double, 6, 6> Ci = C.inverse();
    mat3(B.pinv, 2 * a) = Ci.topLeftCorner<3, 3>();
    mat3(B.pinv, 2 * a + 1) = Ci.topRightCorner<3, 3>();
  });
}

Eigen::Vector3d LatticeDynamics::substep_drift(int v, double h) const {
  Eigen::Vector3d u = drift_.row(v).transpose();
  // A floor contact ends the substep on the floor (B&W's position alteration y = h u), lifted
  // only by the crumple: this also lands a contact that starts above the floor.
  // Static friction also holds it in place against the crumple's sliding: the crumple lifts a
  // resting sheet off the table but does not drag it across. Without this, repeated crumples
  // with plastic rest lengths walk a sheet across the floor like an inchworm.
  if (slot_[v] >= 0 && contact_(v) >= 0.0) {
    u.z() = std::max(u.z(), 0.0) + (floor_at(v) - lat_.positions()(v, 2)) / h;
    if (p_.friction > 0.0) u.x() = u.y() = 0.0;
  }
  return u;
}

void LatticeDynamics::implicit_rhs(double h) {
  // b = h (f + h K w), w = v + substep drift: K w is the force change along the motion.
  Buffers B = buffers(work_, sa_.size(), n_);
  const int na = static_cast<int>(active_.size());
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    const Eigen::Vector3d wv = vel_.row(v).transpose() + substep_drift(v, h);
    Eigen::Vector3d Kw = Eigen::Vector3d::Zero();
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
      const int o = inc_other_[q];
      const Eigen::Vector3d wo = vel_.row(o).transpose() + substep_drift(o, h);
      Kw -= load_sym(B.jac + 6 * inc_spring_[q]) * (wv - wo);
    }
    vec3(B.b, a) = h * (vec3(B.f, a) + h * Kw);
    filter(v, B.b + 3 * a);
  });
}

bool LatticeDynamics::add_landings(double h) {
  // The contact test before the solve sees only vertices already on the floor, with an explicit
  // guess of their velocity. A vertex a hair above the floor (lifted by a crumple, or by
  // rounding), or one the guess let go, is free in the solve, and a frame-sized substep then
  // carries it, and its whole couple, far below the floor (g dt^2 = 17 mm at 1/24 s); projecting
  // both layers back onto the floor flattened the couple. Such vertices become contacts and the
  // system is solved again. Of a couple only the vertex that ends lower lands first: its partner
  // is below the floor only because it fell with it, and the stiff top-bottom spring holds it
  // once the lower one is stopped (it lands in a later round if it still goes below).
  if (!p_.has_floor) return false;
  Buffers B = buffers(work_, sa_.size(), n_);
  const RowMatX3& x = lat_.positions();
  auto end_z = [&](int v) {  // where the solution takes v this substep
    const int a = slot_[v];
    if (a < 0) return x(v, 2);
    return x(v, 2) + h * (vel_(v, 2) + B.dv[3 * a + 2] + substep_drift(v, h).z());
  };
  list_.clear();
  for (int v : active_) {
    if (contact_(v) >= 0.0) continue;
    const double z = end_z(v);
    const int partner = v ^ 1;
    const bool partner_down = slot_[partner] >= 0 && contact_(partner) >= 0.0;
    if (z < floor_at(v) && (partner_down || z <= end_z(partner))) list_.push_back(v);
  }
  for (int v : list_) {  // after the loop: the test above reads contact_ of partners
    const int a = slot_[v];
    contact_(v) = std::max(0.0, -(vel_(v, 2) + B.dv[3 * a + 2]));
    B.dv[3 * a + 2] = -vel_(v, 2);
  }
  return !list_.empty();
}

void LatticeDynamics::apply_A(double h, const double* in, double* out) {
  Buffers B = buffers(work_, sa_.size(), n_);
  const int na = static_cast<int>(active_.size());
  const double h2 = h * h;
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    Eigen::Vector3d y = mat3(B.diag, a) * Eigen::Map<const Eigen::Vector3d>(in + 3 * a);
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
      const int so = slot_[inc_other_[q]];
      if (so >= 0)
        y -= h2 * load_sym(B.jac + 6 * inc_spring_[q]) * Eigen::Map<const Eigen::Vector3d>(in + 3 * so);
    }
    vec3(out, a) = y;
  });
}

void LatticeDynamics::precondition(const double* in, double* out) {
  Buffers B = buffers(work_, sa_.size(), n_);
  const int na = static_cast<int>(active_.size());
  if (precond_ldlt_) {
    // z = S P S r: the filter S zeroes the contacts' v_z in and out. Vertices of the factored
    // set go through the factor (the others of that set see a zero residual), the rest through
    // their diagonal block.
    Factor& f = *factor_;
    f.rhs.setZero();
    for (int a = 0; a < na; ++a) {
      const int fs = f.slot[active_[a]];
      if (fs < 0) continue;
      for (int i = 0; i < 3; ++i) f.rhs[3 * fs + i] = in[3 * a + i];
      filter(active_[a], f.rhs.data() + 3 * fs);
    }
    f.ldlt.solve(f.rhs.data());
    for (int a = 0; a < na; ++a) {
      const int fs = f.slot[active_[a]];
      if (fs >= 0)
        vec3(out, a) = Eigen::Map<const Eigen::Vector3d>(f.rhs.data() + 3 * fs);
      else
        vec3(out, a) = mat3(B.pinv, 2 * a) * Eigen::Map<const Eigen::Vector3d>(in + 3 * a);
      filter(active_[a], out + 3 * a);
    }
    return;
  }
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a], pa = slot_[v ^ 1];
    Eigen::Vector3d y = mat3(B.pinv, 2 * a) * Eigen::Map<const Eigen::Vector3d>(in + 3 * a);
    if (pa >= 0) y += mat3(B.pinv, 2 * a + 1) * Eigen::Map<const Eigen::Vector3d>(in + 3 * pa);
    filter(v, y.data());  // the filter of Baraff and Witkin's modified PCG
    vec3(out, a) = y;
  });
}

bool LatticeDynamics::use_ldlt() const {
  if (p_.preconditioner == Preconditioner::Auto) return static_cast<int>(active_.size()) <= p_.ldlt_max_vertices;
  return p_.preconditioner == Preconditioner::Ldlt;
}

void LatticeDynamics::factor_pattern() {
  Factor& f = *factor_;
  if (f.analysed && f.active == active_) return;
  const int na = static_cast<int>(active_.size());
  f.active = active_;
  f.slot = slot_;
  f.valid = false;
  f.blk_start.assign(1, 0);
  f.blk_row.clear();
  f.blk_spring.clear();
  for (int a = 0; a < na; ++a) {
    const int v = active_[a];
    f.sort_buf.clear();
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q)
      if (slot_[inc_other_[q]] > a) f.sort_buf.emplace_back(slot_[inc_other_[q]], inc_spring_[q]);
    std::sort(f.sort_buf.begin(), f.sort_buf.end());  // rows ascending within each column
    f.blk_row.push_back(a);
    f.blk_spring.push_back(-1);
    for (const auto& [row, spring] : f.sort_buf) {
      f.blk_row.push_back(row);
      f.blk_spring.push_back(spring);
    }
    f.blk_start.push_back(static_cast<int>(f.blk_row.size()));
  }
  f.values.resize(9 * f.blk_row.size());
  f.rhs.resize(3 * na);
  f.ldlt.analyze(na, f.blk_start, f.blk_row);
  f.analysed = true;
}

void LatticeDynamics::factor_fill(double h) {
  // A = M (1 + h c) + h W + h^2 J, with each floor contact's v_z row and column replaced by the
  // identity, as the filtered conjugate gradients see it. Blocks are written column-major.
  Factor& f = *factor_;
  Buffers B = buffers(work_, sa_.size(), n_);
  const int na = static_cast<int>(active_.size());
  const double h2 = h * h;
  const int sym[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};  // store_sym's layout
  for (int a = 0; a < na; ++a) {
    const int va = active_[a];
    for (int b = f.blk_start[a]; b < f.blk_start[a + 1]; ++b) {
      const int r = f.blk_row[b];
      const int vr = active_[r];
      double* val = f.values.data() + 9 * b;
      if (r == a) {
        const auto D = mat3(B.diag, a);
        for (int i = 0; i < 3; ++i)
          for (int ii = 0; ii < 3; ++ii)
            val[3 * i + ii] = (filtered(va, i) || filtered(va, ii)) ? (ii == i ? 1.0 : 0.0) : D(ii, i);
        continue;
      }
      const double* J = B.jac + 6 * f.blk_spring[b];
      for (int i = 0; i < 3; ++i)
        for (int ii = 0; ii < 3; ++ii)
          val[3 * i + ii] = (filtered(va, i) || filtered(vr, ii)) ? 0.0 : -h2 * J[sym[ii][i]];
    }
  }
}

void LatticeDynamics::refresh_factor(double h) {
  // A factor of another active set F still preconditions this one, S: F's part of the residual
  // goes through A_FF^-1, the vertices outside F through their diagonal blocks (an SPD block
  // diagonal). It is refactored when it is stale, or when S and F differ by more than a quarter.
  Factor& f = *factor_;
  if (f.valid && !f.stale) {
    int outside = 0;
    for (int v : active_) outside += f.slot[v] < 0;
    const int ns = static_cast<int>(active_.size()), nf = static_cast<int>(f.active.size());
    if (4 * outside <= ns && nf - (ns - outside) <= ns / 4) return;
  }
  factor_pattern();
  factor_fill(h);
  // A failure is not expected (A is symmetric positive definite); the solve then falls back to
  // Jacobi.
  f.valid = f.ldlt.factorize(f.values.data());
  ++factorizations_;
  f.stale = false;
}

int LatticeDynamics::implicit_solve(double h) {
  Buffers B = buffers(work_, sa_.size(), n_);
  const int na = static_cast<int>(active_.size());
  const bool ldlt = use_ldlt();
  if (ldlt) refresh_factor(h);
  precond_ldlt_ = ldlt && factor_->valid;
  if (!precond_ldlt_) {
    build_jacobi(h);
  } else {
    // Vertices outside the factored set are preconditioned by their diagonal block.
    for (int a = 0; a < na; ++a)
      if (factor_->slot[active_[a]] < 0) mat3(B.pinv, 2 * a) = mat3(B.diag, a).inverse();
  }
  const int N = 3 * na;
  auto axpy = [&](double alpha, const double* xv, double* y) {  // y += alpha x
    parallel_for(0, N, kAxpyCost, [&](long i) { y[i] += alpha * xv[i]; });
  };
  // Modified PCG (Baraff and Witkin 1998) from the start value in B.dv: constrained DOFs start
  // at their prescribed value (v_z -> 0) and every search direction is filtered to leave them
  // there.
  apply_A(h, B.dv, B.Ap);
  for (int i = 0; i < N; ++i) B.r[i] = B.b[i] - B.Ap[i];
  for (int a = 0; a < na; ++a) {
    filter(active_[a], B.r + 3 * a);
    filter(active_[a], B.b + 3 * a);
  }
  int iterations = 0;
  const double rnorm0 = std::sqrt(det_dot(B.r, B.r, N, B.partial));
  const double ref = std::max(rnorm0, std::sqrt(det_dot(B.b, B.b, N, B.partial)));
  // Absolute floor: a residual below cg_velocity_tolerance times the mass norm changes the
  // velocities by less than about that (A >= M), whatever rounding-level right-hand side a
  // resting sheet has; without it such a sheet would iterate on rounding noise.
  double mass2 = 0.0;
  for (int v : active_) mass2 += 3.0 * mass_(v) * mass_(v);
  const double floor_abs = p_.cg_velocity_tolerance * std::sqrt(mass2);
  if (rnorm0 > floor_abs) {
    precondition(B.r, B.p);
    double rz = det_dot(B.r, B.p, N, B.partial);
    while (iterations < p_.cg_max_iterations) {
      ++iterations;
      apply_A(h, B.p, B.Ap);
      for (int a = 0; a < na; ++a)
        filter(active_[a], B.Ap + 3 * a);
      const double pAp = det_dot(B.p, B.Ap, N, B.partial);
      if (!(pAp > 0.0)) break;
      const double alpha = rz / pAp;
      axpy(alpha, B.p, B.dv);
      axpy(-alpha, B.Ap, B.r);
      const double rn = std::sqrt(det_dot(B.r, B.r, N, B.partial));
      if (rn <= p_.cg_tolerance * ref || rn <= floor_abs) break;
      precondition(B.r, B.z);
      const double rz_new = det_dot(B.r, B.z, N, B.partial);
      const double beta = rz_new / rz;
      rz = rz_new;
      parallel_for(0, N, kAxpyCost, [&](long i) { B.p[i] = B.z[i] + beta * B.p[i]; });
    }
  }
  if (precond_ldlt_ && iterations > p_.refactor_iterations) factor_->stale = true;
  return iterations;
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
      if (r > 0.0) {
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
  Buffers B = buffers(work_, sa_.size(), n_);
  // Warm start from the previous substep's acceleration (a smooth motion changes it little);
  // constrained DOFs start at their prescribed value.
  for (int a = 0; a < na; ++a) {
    const int v = active_[a];
    Eigen::Vector3d d0 = h * accel_.row(v).transpose();
    for (int i = 0; i < 3; ++i)
      if (filtered(v, i)) d0(i) = -vel_(v, i);
    vec3(B.dv, a) = d0;
  }
  int iterations = implicit_solve(h);
  // Vertices the solution takes below the floor become contacts, and the system is solved
  // again from the last solution (each round adds at least one; rarely more than one round).
  for (int round = 1; round < kMaxContactRounds && add_landings(h); ++round) {
    implicit_rhs(h);
    iterations += implicit_solve(h);
  }
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    const Eigen::Vector3d u = substep_drift(v, h);  // before x changes: it reads x
    vel_.row(v) += vec3(B.dv, a).transpose();
    accel_.row(v) = vec3(B.dv, a).transpose() / h;
    x.row(v) += h * (vel_.row(v) + u.transpose());
    // A contact lands exactly on the floor (+ the crumple's lift), not a rounding below or
    // above it, so that the next substep's contact test finds it there.
    if (contact_(v) >= 0.0) x(v, 2) = floor_at(v) + h * std::max(drift_(v, 2), 0.0);
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

void LatticeDynamics::apply_floor(double h) {
  if (!p_.has_floor) return;
  RowMatX3& x = lat_.positions();
  const bool implicit = is_implicit(p_.integrator);
  for (int v : active_) {
    // Coulomb friction: the tangential speed drops by friction times the normal speed the
    // floor removed (from the contact filter, or from the projection below).
    double removed = -1.0;
    if (implicit && contact_(v) >= 0.0) removed = contact_(v);
    if (x(v, 2) < floor_at(v)) {
      removed = std::max(0.0, -vel_(v, 2));
      x(v, 2) = floor_at(v);
      vel_(v, 2) = std::max(0.0, vel_(v, 2));
    }
    if (removed < 0.0) continue;
    const double t = std::hypot(vel_(v, 0), vel_(v, 1));
    const double keep = t > p_.friction * removed ? (t - p_.friction * removed) / t : 0.0;
    vel_(v, 0) *= keep;
    vel_(v, 1) *= keep;
  }
}

void LatticeDynamics::set_colliders(std::shared_ptr<const Colliders> colliders, double margin) {
  require(std::isfinite(margin) && margin >= 0.0,
          "collider margin must be finite and >= 0 m, got " + std::to_string(margin));
  colliders_ = std::move(colliders);
  collider_margin_ = margin;
  collider_version_ = colliders_ ? colliders_->version() : 0;
  std::fill(awake_.begin(), awake_.end(), 1);
}

bool LatticeDynamics::collider_contact(const Eigen::Vector3d& x, ColliderHit& hit) const {
  // A vertex the last projection left at the margin is in contact: the slack covers the
  // rounding of that projection (a mesh's trilinear field is not exactly linear along n).
  constexpr double kSlack = 1e-7;  // m
  if (!colliders_) return false;
  hit = colliders_->query(x);
  return hit.distance < collider_margin_ + kSlack;
}

void LatticeDynamics::apply_colliders(double h) {
  // Projection after the substep, as apply_floor does for the floor (docs/dynamics.md §3.2).
  // The substep's solve did not know the collider, so the vertex's couple partner moved with it
  // into the collider; the partner takes the same correction (the couple moves as one), or the
  // top layer would fall through a resting bottom layer by g h^2 every substep.
  if (!colliders_) return;
  constexpr int kProjections = 3;  // a mesh's field: a second try lands within ~1e-9 m
  RowMatX3& x = lat_.positions();
  const int na = static_cast<int>(active_.size());
  // Per active vertex, dx and dv of its contact (NaN in dx(0): none), computed in parallel.
  RowMatX3& dx = x_contact_;
  RowMatX3& dv = v_contact_;
  dx.resize(na, 3);
  dv.resize(na, 3);
  parallel_for(0, na, kRowCost, [&](long a) {
    const int v = active_[a];
    dx(a, 0) = std::numeric_limits<double>::quiet_NaN();
    Eigen::Vector3d p = x.row(v).transpose();
    ColliderHit hit = colliders_->query(p);
    if (!(hit.distance < collider_margin_)) return;
    for (int k = 0; k < kProjections && hit.distance < collider_margin_; ++k) {
      p += (collider_margin_ - hit.distance) * hit.normal;
      hit = colliders_->query(p);
    }
    const Eigen::Vector3d n = hit.normal;
    const Eigen::Vector3d u = vel_.row(v).transpose();
    const double un = u.dot(n);
    const double removed = std::max(0.0, -un);
    const Eigen::Vector3d ut = u - un * n;
    const double t = ut.norm();
    const double keep = t > hit.friction * removed ? (t - hit.friction * removed) / t : 0.0;
    // Friction acts within the substep: the vertex moves with the tangential speed it keeps,
    // so one held by static friction does not creep down a slope by h^2 g sin(angle) a substep.
    p -= h * (1.0 - keep) * ut;
    dx.row(a) = p.transpose() - x.row(v);
    dv.row(a) = (std::max(un, 0.0) * n + keep * ut - u).transpose();
  });
  // Both vertices of a couple in contact: the deeper one's correction moves both (each its own
  // would squash the couple onto the margin).
  for (int a = 0; a < na; ++a) {
    if (std::isnan(dx(a, 0))) continue;
    const int v = active_[a];
    const int b = slot_[v ^ 1];  // the couple's other vertex, -1 when it does not move
    if (b >= 0 && !std::isnan(dx(b, 0))) {
      const double mine = dx.row(a).squaredNorm(), theirs = dx.row(b).squaredNorm();
      if (mine < theirs || (mine == theirs && (v & 1))) continue;
    }
    x.row(v) += dx.row(a);
    vel_.row(v) += dv.row(a);
    if (b >= 0) {
      x.row(v ^ 1) += dx.row(a);
      vel_.row(v ^ 1) += dv.row(a);
    }
  }
}

int LatticeDynamics::contact_substeps(double dt) const {
  // A vertex that may reach a collider this step stops there while its spring neighbours, in the
  // solve, still move: per substep it may fall (s + |g| h) h into it, s its inward speed. That
  // must stay within kContactTravel of its shortest spring in the sheet's plane, so:
  // |g| h^2 + s h <= L. (max_stretch, 1 by default in a Simulation, lets contacts fall through
  // a couple's thickness: measured, a sheet on a 20 degree slope then slid at half of g sin.)
  constexpr double kContactTravel = 0.1;
  if (!colliders_) return 1;
  const RowMatX3& x = lat_.positions();
  const double g = p_.gravity.norm();
  double need = 1.0;
  for (int v : active_) {
    const double speed = vel_.row(v).norm();
    const ColliderHit hit = colliders_->query(x.row(v).transpose());
    if (!(hit.distance < collider_margin_ + (speed + g * dt) * dt)) continue;
    double L = std::numeric_limits<double>::infinity();
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q)
      if (kind_[inc_spring_[q]] != 3 && rest_len_[inc_spring_[q]] > 0.0) L = std::min(L, rest_len_[inc_spring_[q]]);
    if (!std::isfinite(L)) continue;
    L *= kContactTravel;
    const double s = std::max(0.0, -vel_.row(v).dot(hit.normal));
    const double hmax = g > 0.0 ? (-s + std::sqrt(s * s + 4.0 * g * L)) / (2.0 * g) : (s > 0.0 ? L / s : dt);
    need = std::max(need, std::ceil(dt / hmax));
  }
  return static_cast<int>(std::min(need, double(p_.max_substeps)));
}

int LatticeDynamics::wake_stressed_sleepers(double dt) {
  list_.clear();
  for (int v : active_)
    for (int q = inc_start_[v]; q < inc_start_[v + 1]; ++q) {
      const int o = inc_other_[q];
      if (!awake_[o] && !pinned_[o] && !mark_[o]) {
        mark_[o] = 1;
        list_.push_back(o);
      }
    }
  int woke = 0;
  for (int o : list_) {
    mark_[o] = 0;
    const Eigen::Vector3d f = supported(o, vertex_force(o, lat_.positions(), vel_));
    if (f.norm() / mass_(o) * dt >= p_.sleep_speed) {
      awake_[o] = 1;
      // Woken within wake_hold steps of falling asleep: it flickers, so it stays awake, each
      // time it flickers again twice as long (up to kMaxHold steps).
      if (steps_ - slept_at_[o] <= p_.wake_hold) {
        hold_len_[o] = static_cast<std::uint16_t>(std::clamp(2 * int(hold_len_[o]), p_.wake_hold, kMaxHold));
        hold_[o] = hold_len_[o];
      } else {
        hold_len_[o] = 0;
      }
      ++woke;
    }
  }
  return woke;
}

void LatticeDynamics::update_sleep(double dt) {
  const RowMatX3& x = lat_.positions();
  const int na = static_cast<int>(active_.size());
  // A vertex sleeps when it, and every spring neighbour, is slower than sleep_speed, it was not
  // forced this step, and its net force (floor reaction included) would not bring it to
  // sleep_speed within a step.
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    if (hold_[v] > 0) --hold_[v];
    bool quiet = hold_[v] == 0 && !forced_[v] && vel_.row(v).norm() < p_.sleep_speed;
    for (int q = inc_start_[v]; quiet && q < inc_start_[v + 1]; ++q)
      quiet = vel_.row(inc_other_[q]).norm() < p_.sleep_speed;
    if (quiet) quiet = supported(v, vertex_force(v, x, vel_)).norm() / mass_(v) * dt < p_.sleep_speed;
    mark_[v] = quiet ? 1 : 0;
  });
  // Regions sleep, not stragglers: when the quiet vertices are under 1/kSleepShare of the awake
  // set, none sleeps this step. A few sleepers inside a moving sheet save little and cost a
  // redone step or a new factorization each time the motion stresses them awake.
  int quiet_count = 0;
  for (int v : active_) quiet_count += mark_[v];
  const bool bulk = quiet_count * kSleepShare >= na;
  for (int v : active_) {
    if (mark_[v] && bulk) {
      awake_[v] = 0;
      slept_at_[v] = steps_;
      vel_.row(v).setZero();
      accel_.row(v).setZero();
    }
    mark_[v] = 0;
  }
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
  factorizations_ = 0;
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
  for (int v = 0; v < n_; ++v)
    forced_[v] = disp_.row(v).squaredNorm() > 0.0 || (p_.bimetal && delta_(v / 2) != 0.0) ||
                 std::abs(p_.buoyancy * (heat_(v) - heat_prev_(v))) * dt >= p_.sleep_speed;
  if (bimetal && bimetal_all_) std::fill(awake_.begin(), awake_.end(), 1);
  if (colliders_ && colliders_->version() != collider_version_) {  // a collider moved
    std::fill(awake_.begin(), awake_.end(), 1);
    collider_version_ = colliders_->version();
  }
  if (!p_.sleeping)
    std::fill(awake_.begin(), awake_.end(), 1);
  else
    wake_around_forcing();
  drift_ = disp_ / dt;
  const bool plastic = crumple && !p_.bimetal && p_.plasticity > 0.0;
  if (plastic || bimetal) {
    rest_save_ = rest_len_;
    if (membrane_) membrane_rest_save_ = membrane_->rest();
  }
  if (bimetal) apply_bimetal(D, bimetal_all_);
  bool plastic_done = false;
  try {
    for (int pass = 1;; ++pass) {
      collect_active();
      st.passes = pass;
      st.awake = static_cast<int>(active_.size());
      st.omega_max = omega_bound(active_);
      st.substeps = active_.empty() ? 0 : choose_substeps(dt, st.omega_max, max_damping_rate());
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
      const int woke = wake_stressed_sleepers(dt);
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
  st.factorizations = factorizations_;
  D_prev_ = D;
  if (p_.sleeping) update_sleep(dt);
  ++steps_;
  for (int v = 0; v < n_; ++v)
    if (awake_[v]) heat_prev_(v) = heat_(v);
  return st;
}

}  // namespace thinburn
