// The Simulation's shell half (paper §4): the FFD lattice draped over the sheet, the cells'
// mass mapped onto it, fire particles, heat and pyrolysis, the rotation D and the motion.
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "simulation.hpp"

namespace thinburn {
namespace {

constexpr int kPaperCells = 128;  // the paper's grid: 128 x 128 cells (§5)

// M from the sheet: one couple per 16 cells (the paper's Fig. 3 lattice is about this coarse;
// each couple averages the heat of many cells) and no finer than 2 cm (finer crumples are
// hardly visible and stiffen the lattice), 4..65 per side.
int choose_lattice(int N, double size_u, double size_v) {
  const int by_cells = N / 16 + 1;
  const int by_size = static_cast<int>(std::min(size_u, size_v) / 0.02) + 1;
  return std::clamp(std::min(by_cells, by_size), 4, 65);
}

}  // namespace

void Simulation::bilinear_couples(double s, double t, int* couple, double* w) const {
  const int i0 = std::clamp(static_cast<int>(std::floor(s)), 0, M_ - 2);
  const int j0 = std::clamp(static_cast<int>(std::floor(t)), 0, M_ - 2);
  const double a = std::clamp(s - i0, 0.0, 1.0), b = std::clamp(t - j0, 0.0, 1.0);
  couple[0] = i0 * M_ + j0;
  couple[1] = i0 * M_ + j0 + 1;
  couple[2] = (i0 + 1) * M_ + j0;
  couple[3] = (i0 + 1) * M_ + j0 + 1;
  w[0] = (1 - a) * (1 - b);
  w[1] = (1 - a) * b;
  w[2] = a * (1 - b);
  w[3] = a * b;
}

RowMatX3 Simulation::drape_lattice() const {
  // Couple (i, j) sits on the rest surface at parameter (u_j, v_i), its two vertices half the
  // thickness either side along the surface normal; the cell grid is interpolated (and
  // extrapolated half a cell at the border) to find that surface point.
  const int N = sheet_.cells();
  RowMatX3 rest(2 * M_ * M_, 3);
  auto sample = [&](const RowMatX3& grid, double fr, double fc) {
    const int r0 = std::clamp(static_cast<int>(std::floor(fr)), 0, N - 2);
    const int c0 = std::clamp(static_cast<int>(std::floor(fc)), 0, N - 2);
    const double a = fr - r0, b = fc - c0;
    return Eigen::Vector3d(((1 - a) * (1 - b)) * grid.row(r0 * N + c0) + ((1 - a) * b) * grid.row(r0 * N + c0 + 1) +
                           (a * (1 - b)) * grid.row((r0 + 1) * N + c0) + (a * b) * grid.row((r0 + 1) * N + c0 + 1));
  };
  for (int i = 0; i < M_; ++i)
    for (int j = 0; j < M_; ++j) {
      const double fr = i * sheet_.size_v() / (M_ - 1) / sheet_.dv() - 0.5;
      const double fc = j * sheet_.size_u() / (M_ - 1) / sheet_.du() - 0.5;
      const Eigen::Vector3d mid = sample(sheet_.cell_rest(), fr, fc);
      Eigen::Vector3d n = sample(sheet_.cell_rest_normal(), fr, fc);
      n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : sheet_.frame().n;
      rest.row((i * M_ + j) * 2 + 0) = (mid - 0.5 * thickness_ * n).transpose();
      rest.row((i * M_ + j) * 2 + 1) = (mid + 0.5 * thickness_ * n).transpose();
    }
  return rest;
}

void Simulation::build_shell(const std::vector<std::uint8_t>& pinned) {
  const int N = sheet_.cells();
  M_ = params_.lattice > 0 ? params_.lattice : choose_lattice(N, sheet_.size_u(), sheet_.size_v());
  if (M_ < 2) throw std::invalid_argument("lattice must be >= 2");
  const double spacing = std::min(sheet_.size_u(), sheet_.size_v()) / (M_ - 1);
  thickness_ = params_.lattice_thickness > 0 ? params_.lattice_thickness : 0.25 * spacing;
  lattice_ = std::make_unique<FfdLattice>(M_, drape_lattice());

  const RowMatX2& vp = sheet_.vertex_param();
  RowMatX3 coords(vp.rows(), 3);
  for (Eigen::Index i = 0; i < vp.rows(); ++i) {
    const Eigen::Vector2d st = sheet_.lattice_st(vp(i, 0), vp(i, 1), M_);
    coords.row(i) << st.x(), st.y(), 0.5;
  }
  vertex_embedding_ = lattice_->embed(coords, sheet_.vertices());

  // Cell masses and areas onto the couples, half to each layer.
  control_mass_ = Eigen::VectorXd::Zero(2 * M_ * M_);
  control_area_ = Eigen::VectorXd::Zero(2 * M_ * M_);
  burnt_area_ = Eigen::VectorXd::Zero(2 * M_ * M_);
  for (int c = 0; c < N * N; ++c) {
    if (!sheet_.inside()[c]) continue;
    add_cell_mass(c, mass_[c]);
    add_cell_area(c, control_area_);
  }

  DynamicsParams dp = params_.dynamics;
  // The mid-surface rests on the floor, so the bottom layer is held half a thickness lower.
  dp.has_floor = params_.has_floor;
  dp.floor_z = params_.floor_z - 0.5 * thickness_;
  dynamics_ = std::make_unique<LatticeDynamics>(*lattice_, dp);
  mass_dirty_ = true;
  dynamics_->set_areas(control_area_);

  if (!pinned.empty()) {
    // A pinned vertex holds every couple its position depends on, both layers.
    std::vector<std::uint8_t> pin(2 * M_ * M_, 0);
    for (Eigen::Index i = 0; i < vp.rows(); ++i) {
      if (!pinned[i]) continue;
      int cp[4];
      double w[4];
      const Eigen::Vector2d st = sheet_.lattice_st(vp(i, 0), vp(i, 1), M_);
      bilinear_couples(st.x(), st.y(), cp, w);
      for (int k = 0; k < 4; ++k)
        if (w[k] > 1e-12) pin[2 * cp[k]] = pin[2 * cp[k] + 1] = 1;
    }
    dynamics_->set_pinned(pin);
  }
  ParticleParams pp = params_.particles;
  pp.seed = params_.seed ^ 0x5bd1e995ULL;
  particles_ = std::make_unique<ParticleSystem>(pp);
  // Eq 3 sums over the ignition points, the burning cells: the same fire at twice the grid
  // resolution has four times the points. Each cell counts as its share of a cell of the
  // paper's 128 x 128 grid, so pyrolysis (and the bend) does not depend on N, and N = 128
  // is the paper's Cp.
  BendingParams bp = params_.bending;
  const double per_paper_cell = static_cast<double>(kPaperCells) / N;
  bp.cp *= per_paper_cell * per_paper_cell;
  bending_ = std::make_unique<Bending>(M_ * M_, bp);
}

void Simulation::cell_couples(int cell, int* couple, double* w) const {
  const int N = sheet_.cells();
  const Eigen::Vector2d st = sheet_.lattice_st((cell % N + 0.5) * sheet_.du(), (cell / N + 0.5) * sheet_.dv(), M_);
  bilinear_couples(st.x(), st.y(), couple, w);
}

void Simulation::add_cell_mass(int cell, double dm) {
  int cp[4];
  double w[4];
  cell_couples(cell, cp, w);
  for (int k = 0; k < 4; ++k) {
    control_mass_[2 * cp[k]] += 0.5 * w[k] * dm;
    control_mass_[2 * cp[k] + 1] += 0.5 * w[k] * dm;
  }
  mass_dirty_ = true;
}

void Simulation::add_cell_area(int cell, Eigen::VectorXd& onto) const {
  int cp[4];
  double w[4];
  cell_couples(cell, cp, w);
  for (int k = 0; k < 4; ++k)
    for (int layer = 0; layer < 2; ++layer) onto[2 * cp[k] + layer] += 0.5 * w[k] * sheet_.du() * sheet_.dv();
}

void Simulation::set_dynamics_params(const DynamicsParams& p) {
  if (!dynamics_) throw std::invalid_argument("dynamics: this simulation has no shell");
  DynamicsParams dp = p;
  dp.has_floor = params_.has_floor;
  dp.floor_z = params_.floor_z - 0.5 * thickness_;
  dynamics_->set_params(dp);
  params_.dynamics = p;
}

const RowMatX3& Simulation::lattice_positions() const {
  if (!lattice_) throw std::invalid_argument("lattice: this simulation has no shell");
  return lattice_->positions();
}

double Simulation::flame_side(int cell) const {
  // Flames sit on the upper face of a burning cell; on a near-vertical cell the face is a
  // seeded coin toss, which is what lets a hanging sheet crumple both ways.
  const double nz = cell_normal(cell).z();
  if (std::abs(nz) > 0.2) return nz > 0 ? 1.0 : -1.0;
  return hash_uniform(3, static_cast<std::uint64_t>(cell)) >= 0 ? 1.0 : -1.0;
}

void Simulation::emit_particles(double dt) {
  // Emitters: the fringe (paper §3.1), each a cell's worth of front length.
  fringe_into(fringe_buf_);
  const Eigen::Index k = static_cast<Eigen::Index>(fringe_buf_.size());
  emit_pos_.resize(k, 3);
  emit_normal_.resize(k, 3);
  emit_len_.setConstant(k, std::sqrt(sheet_.du() * sheet_.dv()));
  for (Eigen::Index e = 0; e < k; ++e) {
    emit_pos_.row(e) = cell_position(fringe_buf_[e]).transpose();
    emit_normal_.row(e) = cell_normal(fringe_buf_[e]).transpose();
  }
  if (k > 0) particles_->emit(emit_pos_, emit_normal_, emit_len_, dt);
  particles_->step(dt, wind_);
}

void Simulation::update_pyrolysis() {
  // Ignition points (paper §3.1: the burning cells), on their flame face.
  ignition_pts_.resize(static_cast<Eigen::Index>(burning_.size()), 3);
  for (std::size_t b = 0; b < burning_.size(); ++b) {
    const int c = burning_[b];
    ignition_pts_.row(b) = (cell_position(c) + 0.5 * thickness_ * flame_side(c) * cell_normal(c)).transpose();
  }
  bending_->set_pyrolysis(lattice_->positions(), ignition_pts_);
}

void Simulation::step_shell(double dt) {
  emit_particles(dt);
  particle_pos_ = particles_->positions();
  particle_temp_ = particles_->temperatures();
  bending_->add_particle_heat(lattice_->positions(), particle_pos_, particle_temp_, dt);
  update_pyrolysis();
  if (mass_dirty_) {
    // Couples outside the outline carry no sheet; a small floor keeps them integrable.
    const double floor_mass = 1e-3 * control_mass_.maxCoeff();
    dynamics_->set_masses(control_mass_.cwiseMax(floor_mass));
    mass_dirty_ = false;
  }
  if (strength_dirty_) {
    // Ash holds little together (Fig. 9's cloth sinks as it burns): a control vertex keeps
    // ash_strength of its springs' stiffness over the burnt share of the sheet it carries.
    strength_.resize(control_area_.size());
    for (Eigen::Index v = 0; v < strength_.size(); ++v) {
      const double burnt = control_area_[v] > 0 ? std::min(1.0, burnt_area_[v] / control_area_[v]) : 0.0;
      strength_[v] = 1.0 - (1.0 - params_.ash_strength) * burnt;
    }
    dynamics_->set_strength(strength_);
    strength_dirty_ = false;
  }
  dynamics_->set_wind(wind_);
  bending_->rotation(rotation_);
  // Far from the fire D creeps by micro-radians as faint heat arrives; passing those on would
  // keep the whole lattice awake. A couple's applied rotation follows D in steps of at least
  // kRotationQuantum, so regions at rest sleep while the error stays below that quantum.
  constexpr double kRotationQuantum = 1e-3;  // rad
  if (applied_rotation_.size() != rotation_.size()) applied_rotation_ = Eigen::VectorXd::Zero(rotation_.size());
  for (Eigen::Index c = 0; c < rotation_.size(); ++c)
    if (std::abs(rotation_[c] - applied_rotation_[c]) >= kRotationQuantum) applied_rotation_[c] = rotation_[c];
  stats_ = dynamics_->step(dt, applied_rotation_, bending_->heat_rate());
}

}  // namespace thinburn
