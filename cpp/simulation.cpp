#include "simulation.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace thinburn {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const StepStats kNoStats{};
const Eigen::VectorXd kNoMasses;

// A stateless hash (splitmix64) so a cell's random draw depends only on the seed and the
// cell, never on the order in which cells are visited.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

Simulation::Simulation(const RowMatX3& vertices, const RowMatX3i& faces, const RowMatX2& uv,
                       const SimulationParams& params, const std::vector<std::uint8_t>& pinned)
    : params_(params),
      sheet_(vertices, faces, uv, params.cells),
      front_(params.cells, params.cells, sheet_.dv(), sheet_.du(), params.front) {
  if (!(params.v0 > 0)) throw std::invalid_argument("v0 must be > 0");
  if (!(params.burn_duration > 0)) throw std::invalid_argument("burn_duration must be > 0");
  if (!(params.ash_strength >= 0 && params.ash_strength <= 1)) throw std::invalid_argument("ash_strength must be in [0, 1]");
  const int nc = sheet_.num_cells();
  front_.set_inside(sheet_.inside());
  state_.assign(nc, kUnburnt);
  duration_.resize(nc);
  v_scale_.resize(nc);
  mass_.assign(nc, 0.0);
  const double cell_mass = params.areal_density * sheet_.du() * sheet_.dv();
  for (int c = 0; c < nc; ++c) {
    duration_[c] = params.burn_duration * std::max(0.1, 1.0 + params.duration_noise * noise(c, 1));
    v_scale_[c] = std::max(0.1, 1.0 + params.speed_noise * noise(c, 2));
    if (sheet_.inside()[c]) mass_[c] = cell_mass;
  }
  speed_fn_ = [this](int cell) { return local_speed(cell); };
  if (!pinned.empty() && pinned.size() != static_cast<std::size_t>(vertices.rows()))
    throw std::invalid_argument("pinned: one flag per vertex expected");
  if (params.shell) shell_ = std::make_unique<Shell>(sheet_, shell_params(), mass_, pinned);
  build_locator();
}

ShellParams Simulation::shell_params() const {
  ShellParams sp;
  sp.lattice = params_.lattice;
  sp.lattice_thickness = params_.lattice_thickness;
  sp.has_floor = params_.has_floor;
  sp.floor_z = params_.floor_z;
  sp.ash_strength = params_.ash_strength;
  sp.seed = params_.seed;
  sp.dynamics = params_.dynamics;
  sp.particles = params_.particles;
  sp.bending = params_.bending;
  return sp;
}

void Simulation::build_locator() {
  // Buckets: the lattice's control cells (a cell moves with its quad's four couples), or
  // blocks of kBlock x kBlock cells on a sheet that never moves.
  constexpr int kBlock = 4 * CellLocator::kBlock;
  const int N = sheet_.cells(), nc = sheet_.num_cells();
  std::vector<int> bucket(nc);
  int buckets;
  if (shell_) {
    const int M = shell_->size();
    buckets = (M - 1) * (M - 1);
    for (int c = 0; c < nc; ++c) {
      int cp[4];
      double w[4];
      shell_->cell_couples(c, cp, w);
      bucket[c] = (cp[0] / M) * (M - 1) + cp[0] % M;
    }
  } else {
    const int nb = (N + kBlock - 1) / kBlock;
    buckets = nb * nb;
    for (int c = 0; c < nc; ++c) bucket[c] = (c / N / kBlock) * nb + (c % N) / kBlock;
  }
  locator_ = std::make_unique<CellLocator>(N, sheet_.cell_rest(), sheet_.inside(), bucket, buckets);
  locator_stale_ = shell_ != nullptr;
}

void Simulation::refresh_locator() const {
  if (!locator_stale_) return;
  RowMatX3 lo, hi;
  shell_->quad_displacement_bounds(lo, hi);
  locator_->set_displacement_bounds(lo, hi);
  locator_stale_ = false;
}

double Simulation::hash_uniform(std::uint64_t stream, std::uint64_t key) const {
  const std::uint64_t h = mix(params_.seed ^ mix(stream * 0x100000001b3ULL + key));
  return 2.0 * (static_cast<double>(h >> 11) * 0x1.0p-53) - 1.0;  // uniform in [-1, 1)
}

double Simulation::noise(int cell, std::uint64_t stream) const {
  // Real sheets vary over centimetres, not per cell: mostly a smooth value-noise field
  // (bilinear between random values every kNoiseScale cells), plus a little per-cell grain.
  constexpr int kNoiseScale = 10;
  const int N = sheet_.cells(), r = cell / N, c = cell % N;
  const int gr = r / kNoiseScale, gc = c / kNoiseScale;
  const double fr = (r % kNoiseScale + 0.5) / kNoiseScale, fc = (c % kNoiseScale + 0.5) / kNoiseScale;
  auto node = [&](int i, int j) { return hash_uniform(stream + 7, (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j)); };
  const double smooth = (1 - fr) * ((1 - fc) * node(gr, gc) + fc * node(gr, gc + 1)) +
                        fr * ((1 - fc) * node(gr + 1, gc) + fc * node(gr + 1, gc + 1));
  return 0.75 * smooth + 0.25 * hash_uniform(stream, static_cast<std::uint64_t>(cell));
}

Eigen::Vector3d Simulation::cell_position(int cell) const {
  return shell_ ? shell_->cell_position(cell) : Eigen::Vector3d(sheet_.cell_rest().row(cell).transpose());
}

Eigen::Vector3d Simulation::cell_normal(int cell) const {
  if (!shell_) return sheet_.cell_rest_normal().row(cell).transpose();
  const int N = sheet_.cells(), r = cell / N, c = cell % N;
  const int cl = std::max(c - 1, 0), cr = std::min(c + 1, N - 1), rd = std::max(r - 1, 0), ru = std::min(r + 1, N - 1);
  const Eigen::Vector3d n = (cell_position(r * N + cr) - cell_position(r * N + cl))
                                .cross(cell_position(ru * N + c) - cell_position(rd * N + c));
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d(sheet_.cell_rest_normal().row(cell).transpose());
}

double Simulation::grad2(int cell) const {
  // Rise over run of the current surface out of the rest plane, along rows and columns,
  // from central differences (one-sided at the outline), squared and summed: |grad h|².
  const int N = sheet_.cells(), r = cell / N, c = cell % N;
  const auto& inside = sheet_.inside();
  const Eigen::Vector3d& n = sheet_.frame().n;
  auto slope2 = [&](int a, int b) {
    if (a == b) return 0.0;
    const Eigen::Vector3d d = cell_position(b) - cell_position(a);
    const double rise = d.dot(n), run = (d - rise * n).norm();
    return run > 0 ? (rise * rise) / (run * run) : 0.0;
  };
  auto pick = [&](int rr, int cc) { return (rr >= 0 && rr < N && cc >= 0 && cc < N && inside[rr * N + cc]) ? rr * N + cc : cell; };
  return slope2(pick(r, c - 1), pick(r, c + 1)) + slope2(pick(r - 1, c), pick(r + 1, c));
}

LocalSpeed Simulation::local_speed(int cell) const {
  const double v0 = params_.v0 * v_scale_[cell];
  LocalSpeed s{std::max(params_.v_floor, 1.0 - params_.cv * grad2(cell)) * v0, 0.0, 0.0};
  if (params_.climb == 0.0 && (params_.wind_spread == 0.0 || wind_.isZero())) return s;
  // The drive vector in grid axes: world-up and the wind, projected on the local tangents.
  const int N = sheet_.cells(), r = cell / N, c = cell % N;
  const int cl = std::max(c - 1, 0), cr = std::min(c + 1, N - 1), rd = std::max(r - 1, 0), ru = std::min(r + 1, N - 1);
  Eigen::Vector3d t_col = cell_position(r * N + cr) - cell_position(r * N + cl);
  Eigen::Vector3d t_row = cell_position(ru * N + c) - cell_position(rd * N + c);
  if (t_col.norm() > 0) t_col.normalize();
  if (t_row.norm() > 0) t_row.normalize();
  const Eigen::Vector3d drive = params_.climb * Eigen::Vector3d::UnitZ() + params_.wind_spread * wind_;
  s.e_row = drive.dot(t_row);
  s.e_col = drive.dot(t_col);
  const double e = std::hypot(s.e_row, s.e_col);
  if (e > params_.max_drive) {
    s.e_row *= params_.max_drive / e;
    s.e_col *= params_.max_drive / e;
  }
  return s;
}

int Simulation::ignite(const Eigen::Vector3d& point, double t, double radius) {
  const int N = sheet_.cells();
  const std::vector<int> lit = cells_near(point, radius);
  // The front cannot rewrite cells it has already accepted, so an ignition time before the
  // last step is taken as that step's end: the fire starts now and catches up from there.
  const double t0 = std::max(t, front_.time());
  for (int c : lit) front_.ignite(FrontSource{static_cast<double>(c / N), static_cast<double>(c % N), t0}, speed_fn_);
  return static_cast<int>(lit.size());
}

std::vector<int> Simulation::cells_near(const Eigen::Vector3d& point, double radius) const {
  if (shell_) refresh_locator();
  CellLocator::Found found = locator_->find(point, radius, [this](int c) { return cell_position(c); });
  const int best = found.nearest;
  std::vector<int>& lit = found.within;
  const double reach = std::max({radius, 3.0 * std::max(sheet_.du(), sheet_.dv()), 0.02 * std::sqrt(sheet_.area())});
  if (best < 0 || found.distance > reach)
    throw std::invalid_argument("point: no cell of the sheet lies within " + std::to_string(reach) +
                                " m of the point (nearest is " + std::to_string(found.distance) + " m away)");
  if (lit.empty()) lit.push_back(best);
  return std::move(lit);
}

// Everything a step changes, for the steps that may refuse (Simulation::step_may_throw). The
// dynamics restores its rest lengths and heat itself when it throws.
// Everything a step changes, for the steps that may refuse (Simulation::step_may_throw).
struct Simulation::Saved {
  double time;
  FireFront front;
  std::vector<std::uint8_t> state;
  std::vector<int> burning;
  std::vector<double> mass;
  Shell::Checkpoint shell;
};

bool Simulation::step_may_throw() const {
  // Only an explicit integrator refuses a step (more than max_substeps needed); the implicit one
  // takes any step, so its frames never pay for a copy.
  return shell_ && params_.dynamics.integrator != Integrator::Implicit;
}

Simulation::Saved Simulation::save() const {
  return Saved{time_, front_, state_, burning_, mass_, shell_->checkpoint()};
}

void Simulation::restore(Saved&& s) {
  time_ = s.time;
  front_ = std::move(s.front);
  state_ = std::move(s.state);
  burning_ = std::move(s.burning);
  mass_ = std::move(s.mass);
  shell_->rollback(std::move(s.shell));
  locator_stale_ = true;
}

void Simulation::step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("dt must be > 0 and finite");
  if (!step_may_throw()) return step_unguarded(dt);
  Saved saved = save();
  try {
    step_unguarded(dt);
  } catch (...) {
    restore(std::move(saved));
    throw;
  }
}

void Simulation::step_unguarded(double dt) {
  const double t_end = time_ + dt;
  for (int c : front_.advance(t_end, speed_fn_)) {
    if (state_[c] != kUnburnt) continue;
    state_[c] = kBurning;
    burning_.push_back(c);
  }
  time_ = t_end;
  retire_burnt();
  if (shell_) step_shell(dt);
  locator_stale_ = shell_ != nullptr;
}

void Simulation::retire_burnt() {
  const auto& arrival = front_.arrival();
  const double keep = params_.ash_fraction;
  std::size_t w = 0;
  for (int c : burning_) {
    if (arrival[c] + duration_[c] <= time_) {
      state_[c] = kBurnt;
      if (shell_) shell_->cell_burnt(c, (1.0 - keep) * mass_[c]);
      mass_[c] *= keep;
    } else {
      burning_[w++] = c;
    }
  }
  burning_.resize(w);
}

std::vector<double> Simulation::ignition_times() const {
  std::vector<double> t(front_.arrival());
  for (std::size_t c = 0; c < t.size(); ++c)
    if (state_[c] == kUnburnt) t[c] = kInf;  // accepted only when its time has come
  return t;
}

std::vector<int> Simulation::fringe() const {
  std::vector<int> out;
  fringe_into(out);
  return out;
}

void Simulation::fringe_into(std::vector<int>& out) const {
  // Reuses the caller's buffer: the particle emitters ask for the fringe every step.
  const int N = sheet_.cells();
  const auto& inside = sheet_.inside();
  out.clear();
  for (int c : burning_) {
    const int r = c / N, col = c % N;
    bool edge = false;
    for (int dr = -1; dr <= 1 && !edge; ++dr)
      for (int dc = -1; dc <= 1 && !edge; ++dc) {
        const int rr = r + dr, cc = col + dc;
        if ((dr || dc) && rr >= 0 && rr < N && cc >= 0 && cc < N && inside[rr * N + cc] &&
            state_[rr * N + cc] == kUnburnt)
          edge = true;
      }
    if (edge) out.push_back(c);
  }
  std::sort(out.begin(), out.end());
}

std::vector<double> Simulation::cell_char() const {
  const auto& arrival = front_.arrival();
  std::vector<double> ch(arrival.size(), 0.0);
  for (std::size_t c = 0; c < ch.size(); ++c)
    if (state_[c] != kUnburnt) ch[c] = std::clamp((time_ - arrival[c]) / duration_[c], 0.0, 1.0);
  return ch;
}

RowMatX3 Simulation::cell_positions() const {
  RowMatX3 p(sheet_.num_cells(), 3);
  for (int c = 0; c < sheet_.num_cells(); ++c) p.row(c) = cell_position(c).transpose();
  return p;
}

RowMatX3 Simulation::vertex_positions() const {
  if (!shell_) return sheet_.vertices();
  RowMatX3 out;
  shell_->vertex_positions(out);
  return out;
}

Eigen::VectorXd Simulation::vertex_char() const {
  const std::vector<double> ch = cell_char();
  Eigen::VectorXd out(sheet_.vertices().rows());
  sheet_.cells_to_vertices(ch.data(), out.data());
  return out;
}

Eigen::VectorXd Simulation::vertex_ignition_times() const {
  const std::vector<double> t = ignition_times();
  const auto& vc = sheet_.vertex_cell();
  Eigen::VectorXd out(vc.size());
  for (std::size_t i = 0; i < vc.size(); ++i) out[i] = t[vc[i]];
  return out;
}

Eigen::VectorXd Simulation::vertex_burnout_times() const {
  Eigen::VectorXd out = vertex_ignition_times();
  const auto& vc = sheet_.vertex_cell();
  for (std::size_t i = 0; i < vc.size(); ++i) out[i] += duration_[vc[i]];
  return out;
}

}  // namespace thinburn

namespace thinburn {

const StepStats& Simulation::last_step_stats() const { return shell_ ? shell_->last_step_stats() : kNoStats; }

const Eigen::VectorXd& Simulation::control_masses() const { return shell_ ? shell_->control_masses() : kNoMasses; }

void Simulation::set_dynamics_params(const DynamicsParams& p) {
  if (!shell_) throw std::invalid_argument("dynamics: this simulation has no shell");
  shell_->set_dynamics_params(p);
  params_.dynamics = p;
}

const RowMatX3& Simulation::lattice_positions() const {
  if (!shell_) throw std::invalid_argument("lattice: this simulation has no shell");
  return shell_->lattice().positions();
}

double Simulation::flame_side(int cell) const {
  // Flames sit on the upper face of a burning cell; on a near-vertical cell the face is a
  // seeded coin toss, which is what lets a hanging sheet crumple both ways.
  const double nz = cell_normal(cell).z();
  if (std::abs(nz) > 0.2) return nz > 0 ? 1.0 : -1.0;
  return hash_uniform(3, static_cast<std::uint64_t>(cell)) >= 0 ? 1.0 : -1.0;
}

void Simulation::gather_shell_sources() {
  // Emitters: the fringe (paper §3.1), each a cell's worth of front length. Ignition points
  // (eq 3): the burning cells, on their flame face.
  fringe_into(fringe_buf_);
  const Eigen::Index k = static_cast<Eigen::Index>(fringe_buf_.size());
  emit_pos_.resize(k, 3);
  emit_normal_.resize(k, 3);
  emit_len_.setConstant(k, std::sqrt(sheet_.du() * sheet_.dv()));
  for (Eigen::Index e = 0; e < k; ++e) {
    emit_pos_.row(e) = cell_position(fringe_buf_[e]).transpose();
    emit_normal_.row(e) = cell_normal(fringe_buf_[e]).transpose();
  }
  const double half = 0.5 * shell_->thickness();
  ignition_pts_.resize(static_cast<Eigen::Index>(burning_.size()), 3);
  for (std::size_t b = 0; b < burning_.size(); ++b) {
    const int c = burning_[b];
    ignition_pts_.row(b) = (cell_position(c) + half * flame_side(c) * cell_normal(c)).transpose();
  }
}

void Simulation::step_shell(double dt) {
  gather_shell_sources();
  shell_->step(dt, ShellSources{&emit_pos_, &emit_normal_, &emit_len_, &ignition_pts_}, wind_);
}

}  // namespace thinburn
