#include "simulation.hpp"

#include "heat.hpp"
#include "outside_keeper.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <array>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace thinburn {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const StepStats kNoStats{};
const Eigen::VectorXd kNoMasses;
// A mesh is flat (Geometry::Auto picks the plane) when no vertex lies farther than this share
// of its bounding box's diagonal from the best-fit plane.
constexpr double kFlatTolerance = 1e-4;

bool is_flat(const RowMatX3& V) {
  const Eigen::RowVector3d mean = V.colwise().mean();
  const RowMatX3 d = V.rowwise() - mean;
  const Eigen::Matrix3d cov = d.transpose() * d;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  const Eigen::Vector3d n = es.eigenvectors().col(0);
  const double diag = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  return (d * n).cwiseAbs().maxCoeff() <= kFlatTolerance * diag;
}

std::unique_ptr<FireCells> make_cells(const RowMatX3& V, const RowMatX3i& F, const RowMatX2& uv,
                                      const SimulationParams& p) {
  Geometry g = p.geometry;
  if (g == Geometry::Auto) {
    if (V.rows() < 3 || !V.allFinite()) g = Geometry::Plane;  // the grid's checks name the problem
    else g = is_flat(V) ? Geometry::Plane : Geometry::Surface;
  }
  if (g == Geometry::Plane) return std::make_unique<GridCells>(std::make_shared<const Sheet>(V, F, uv, p.cells), p.front);
  if (p.front == FrontMethod::Cellular8 || p.front == FrontMethod::Cellular16)
    throw std::invalid_argument("front: the cellular rules are defined on a flat grid; use geometry='plane' (a flat "
                                "sheet) or the default front on a curved shell");
  return std::make_unique<ShellCells>(V, F, p.cells);
}

// The parameters, checked before the cells are built from them.
const SimulationParams& validated(const SimulationParams& p) {
  validate(p);
  return p;
}

}  // namespace

const std::vector<param::Field<SimulationParams>>& SimulationParams::fields() {
  using P = SimulationParams;
  using namespace param;
  static const std::vector<Field<P>> table = {
      field("cells", &P::cells, within(2, 4096), "N: N x N grid cells, or about N^2 on a surface"),
      choice("geometry", &P::geometry, "Geometry", {"auto", "plane", "surface"},
             "where the cells and the lattice live (auto: plane for a flat mesh)"),
      choice("front", &P::front, "FrontMethod", {"cellular", "cellular16", "fmm1", "fmm"}, "the grid's fire front"),
      field("seed", &P::seed, "seeds every random draw"),
      field("v0", &P::v0, above(0), "m/s: eq 1's spread speed V0"),
      field("cv", &P::cv, at_least(0), "eq 1 spread coefficient: V = V0 (1 - Cv grad^2)"),
      field("v_floor", &P::v_floor, within(0, 1, true), "share of V0 below which V never falls"),
      field("speed_noise", &P::speed_noise, within(0, 0.9), "relative per-cell jitter of V0 (seeded)"),
      field("burn_duration", &P::burn_duration, above(0), "s a cell burns before it is burnt"),
      field("finish_within", &P::finish_within, at_least(0),
            "s from the first ignition to the last burnout (0: off)"),
      field("ignition_temperature", &P::ignition_temperature, at_least(0),
           "K above ambient at which heat lights an unburnt cell (0: heat does not ignite)"),
      field("ignition_gain", &P::ignition_gain, at_least(0), "m^2/s: eq 2's Ct for the cells' temperature"),
      field("heat_loss", &P::heat_loss, at_least(0), "1/s: the cells' cooling (Newton's law)"),
      field("duration_noise", &P::duration_noise, within(0, 0.9), "relative per-cell jitter of the burn duration"),
      field("climb", &P::climb, within(0, 0.9), "drive toward world-up along the sheet per unit slope"),
      field("wind_spread", &P::wind_spread, at_least(0), "drive per m/s of wind along the sheet"),
      field("max_drive", &P::max_drive, within(0, 0.95), "cap on the drive, so the back fire never stalls"),
      field("areal_density", &P::areal_density, above(0), "kg/m^2"),
      field("ash_fraction", &P::ash_fraction, within(0, 1), "share of its mass a burnt cell keeps"),
      field("ash_strength", &P::ash_strength, within(0, 1),
            "share of the lattice springs' stiffness burnt sheet keeps"),
      field("shell", &P::shell, "the shell: lattice, particles, bending and motion (off: the rest shape)"),
      field("lattice", &P::lattice, within(0, kMaxLattice), "M couples per side (0: chosen)",
            "a step's cost grows as M^2"),
      field("lattice_thickness", &P::lattice_thickness, at_least(0), "m between a couple's two vertices (0: chosen)"),
      field("crease_angle", &P::crease_angle, within(0, 180),
            "degrees: a curved shell's mesh edges turning by more are creases, hinges (180: none)"),
      field("has_floor", &P::has_floor, "a horizontal floor (a table) under the sheet"),
      field("floor_z", &P::floor_z, "m: the floor's height"),
      field("mesh_tolerance", &P::mesh_tolerance, within(0, 1),
            "share of the sheet's size a couple drifts before its mesh vertices are redone (0: exact)"),
      field("imperfection", &P::imperfection, within(0, 0.1),
            "share of the sheet's size it starts bowed by along its normals (0: perfectly flat)"),
  };
  return table;
}

void validate(const SimulationParams& p) {
  param::check_all(SimulationParams::fields(), p);
  validate(p.dynamics);
  validate(p.particles);
  validate(p.bending);
}

Simulation::Simulation(const RowMatX3& vertices, const RowMatX3i& faces, const RowMatX2& uv,
                       const SimulationParams& params, const std::vector<std::uint8_t>& pinned,
                       const CellMaps& maps)
    : params_(validated(params)), vertices_(vertices), faces_(faces), cells_(make_cells(vertices, faces, uv, params)) {
  show_floor_in_dynamics();
  bind_cells();
  const int nc = cells_->size();
  state_.assign(nc, kUnburnt);
  duration_.resize(nc);
  v_scale_.resize(nc);
  mass_.assign(nc, 0.0);
  for (int c = 0; c < nc; ++c) {
    duration_[c] = params.burn_duration * std::max(0.1, 1.0 + params.duration_noise * noise(c, 1));
    v_scale_[c] = std::max(0.1, 1.0 + params.speed_noise * noise(c, 2));
    if (cells_->inside()[c]) mass_[c] = params.areal_density * cells_->area(c);
  }
  if (!pinned.empty() && pinned.size() != static_cast<std::size_t>(vertices.rows()))
    throw std::invalid_argument("pinned: one flag per vertex expected");
  apply_maps(faces, maps);
  if (params.shell) {
    if (grid_)
      shell_ = std::make_unique<Shell>(grid_->sheet(), shell_params(), mass_, pinned);
    else
      shell_ = std::make_unique<Shell>(surface_->surface(), vertices, faces, shell_params(), mass_, pinned);
  }
  build_locator();
  // Pieces: where heat may light a new fire, and which closed pieces burn on their outside.
  if (params.shell || params.ignition_temperature > 0) find_pieces();
  if (params.ignition_temperature > 0) {
    if (!std::isfinite(params.ignition_temperature) || !(params.ignition_gain > 0) || !(params.heat_loss >= 0))
      throw std::invalid_argument("heat ignition: ignition_temperature must be finite, ignition_gain > 0 and heat_loss >= 0");
    cell_temp_.assign(nc, 0.0);
  }
  if (params.finish_within > 0) {
    plan_cells_ = cells_->clone();
    // Each cell burns at most half the time: the rest is for the fire to travel.
    double longest = 0.0;
    for (int c = 0; c < nc; ++c)
      if (cells_->inside()[c] && !is_firebreak(c)) longest = std::max(longest, duration_[c]);
    const double cut = longest > 0 ? std::min(1.0, 0.5 * params.finish_within / longest) : 1.0;
    for (double& d : duration_) d *= cut;
  }
}

void Simulation::find_pieces() {
  // Connected pieces of the cells (8-neighbours on the grid, the cell graph on a surface).
  const int nc = cells_->size();
  piece_.assign(nc, -1);
  const auto& in = cells_->inside();
  std::vector<int> stack;
  int pieces = 0;
  for (int seed = 0; seed < nc; ++seed) {
    if (!in[seed] || piece_[seed] >= 0) continue;
    piece_[seed] = pieces;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      auto visit = [&](int n) {
        if (in[n] && piece_[n] < 0) {
          piece_[n] = pieces;
          stack.push_back(n);
        }
      };
      if (grid_) {
        const int N = grid_->sheet().cells(), r = c / N, col = c % N;
        for (int dr = -1; dr <= 1; ++dr)
          for (int dc = -1; dc <= 1; ++dc)
            if ((dr || dc) && r + dr >= 0 && r + dr < N && col + dc >= 0 && col + dc < N) visit((r + dr) * N + col + dc);
      } else {
        const SurfaceCells& sc = surface_->surface();
        for (int q = sc.nbr_offset()[c]; q < sc.nbr_offset()[c + 1]; ++q) visit(sc.nbr_index()[q]);
      }
    }
    ++pieces;
  }
  piece_alight_.assign(pieces, 0);
  find_outsides(pieces);
}

void Simulation::find_outsides(int pieces) {
  // A closed piece of a surface burns on its outside (outside_keeper.hpp): the up rule put 80 %
  // of a sphere's flames inside it when lit at its bottom. Per piece, the sign of its cells'
  // normals that points out.
  piece_outside_.assign(pieces, 0.0);
  if (grid_) return;
  const SurfaceCells& sc = surface_->surface();
  std::vector<int> piece = piece_;
  for (int c = 0; c < cells_->size(); ++c)
    if (!cells_->inside()[c]) piece[c] = -1;
  const std::vector<double> sign = outside_signs(piece, sc.on_boundary(), sc.positions(), sc.normals(), sc.areas());
  for (int c = 0; c < cells_->size(); ++c)
    if (piece[c] >= 0) piece_outside_[piece[c]] = sign[c];
}

void Simulation::heat_ignite(double dt) {
  // Eq 2 at the cells where they are now, with the ignition's own Ct: the particles' heat,
  // less Newton cooling. A cell catches fire at the threshold, but only on a piece not yet
  // alight: there eq 1's front is the fire, and heat lighting cells ahead of it would change
  // the paper's spread; across a gap (another sheet, a stack) heat is the only way over.
  if (!(params_.ignition_temperature > 0) || !shell_) return;
  const ParticleSystem& ps = shell_->particles();
  const RowMatX3 where = cell_positions();
  const double keep = std::exp(-params_.heat_loss * dt);
  for (double& t : cell_temp_) t *= keep;
  if (ps.positions().rows() > 0) {
    Eigen::VectorXd gain;
    KernelSumOptions o;
    o.power = 2;
    o.d_min = params_.bending.d_min;
    o.method = params_.bending.fast ? SumMethod::Fast : SumMethod::Direct;
    o.tolerance = params_.bending.tolerance;
    particle_heat(RowMatX3(ps.positions()), Eigen::VectorXd(ps.temperatures()), where, params_.ignition_gain, dt, o,
                  gain);
    for (int c = 0; c < cells_->size(); ++c) cell_temp_[c] += gain[c];
  }
  for (int c : burning_) piece_alight_[piece_[c]] = 1;
  std::vector<int> hot;
  for (int c = 0; c < cells_->size(); ++c)
    if (cells_->inside()[c] && state_[c] == kUnburnt && !piece_alight_[piece_[c]] &&
        cell_temp_[c] >= params_.ignition_temperature)
      hot.push_back(c);
  if (!hot.empty()) ignite_cells(hot, time_);
}

void Simulation::set_fire_sources(const RowMatX3& points, const Eigen::VectorXd& lengths) {
  if (!shell_) throw std::invalid_argument("fire sources: their flames are fire particles, which need shell=True");
  if (points.rows() != lengths.size())
    throw std::invalid_argument("fire sources: one length per point expected (" + std::to_string(points.rows()) +
                                " points, " + std::to_string(lengths.size()) + " lengths)");
  if (!points.allFinite() || !lengths.allFinite() || (lengths.array() < 0).any())
    throw std::invalid_argument("fire sources: points must be finite and lengths finite and >= 0");
  source_pos_ = points;
  source_len_ = lengths;
}

void Simulation::note_sources(const std::vector<int>& lit, double t0) {
  if (!plan_cells_ || lit.empty()) return;
  if (pace_.t0 < 0 || t0 < pace_.t0) pace_.t0 = t0;
  for (int c : lit) {
    auto it = std::lower_bound(pace_.sources.begin(), pace_.sources.end(), c);
    if (it != pace_.sources.end() && *it == c) continue;
    pace_.sources.insert(it, c);
    pace_.stale = true;
  }
}

void Simulation::replan() {
  // Arrival times over the rest shape from every source at once, at the painted speeds with
  // no slope factor and no drive: how far each cell is, in seconds of the material's speed.
  std::unique_ptr<FireCells> f = plan_cells_->clone();
  SpreadLaw law;
  law.v = [this](int c) { return params_.v0 * v_scale_[c]; };
  CellView rest;
  rest.position = [&f](int c) { return f->rest(c); };
  rest.normal = [&f](int c) { return f->rest_normal(c); };
  rest.reference_normal = rest.normal;
  for (int c : pace_.sources) f->ignite(c, 0.0, law, rest);
  f->advance(std::numeric_limits<double>::max(), law, rest);
  pace_.tau = f->arrival();
  pace_.order.clear();
  for (int c = 0; c < f->size(); ++c)
    if (std::isfinite(pace_.tau[c]) && cells_->inside()[c]) pace_.order.push_back(c);
  std::sort(pace_.order.begin(), pace_.order.end(), [this](int a, int b) {
    return pace_.tau[a] < pace_.tau[b] || (pace_.tau[a] == pace_.tau[b] && a < b);
  });
  pace_.cum.resize(pace_.order.size());
  double sum = 0.0;
  for (std::size_t k = 0; k < pace_.order.size(); ++k) pace_.cum[k] = (sum += cells_->area(pace_.order[k]));
  // The last cells to catch fire (the farthest 2 % of the area) burn out last: the spread must
  // end their longest burn before the target (the longest burn anywhere ended most fires
  // 5-10 % early, the duration noise being about that share of a short target).
  double last = 0.0;
  for (std::size_t k = pace_.order.size(); k-- > 0;) {
    last = std::max(last, duration_[pace_.order[k]]);
    if (sum - (k ? pace_.cum[k - 1] : 0.0) >= 0.02 * sum) break;
  }
  pace_.window = params_.finish_within - last;
  pace_.stale = false;
  pace_.has_prev = false;
  pace_.covered = pace_.scaled = 0.0;
}

double Simulation::tau_covered() const {
  // The fire's progress in tau: the tau by which as much reachable area is lit as is lit now.
  // The whole front counts, so a corner the curl slows holds the pace back as it should.
  double lit = 0.0;
  for (int c : pace_.order)
    if (state_[c] != kUnburnt) lit += cells_->area(c);
  if (pace_.order.empty()) return 0.0;
  const auto it = std::lower_bound(pace_.cum.begin(), pace_.cum.end(), lit);
  if (it == pace_.cum.end()) return pace_.tau[pace_.order.back()];
  const std::size_t k = static_cast<std::size_t>(it - pace_.cum.begin());
  const double lo_area = k ? pace_.cum[k - 1] : 0.0, lo_tau = k ? pace_.tau[pace_.order[k - 1]] : 0.0;
  const double share = (lit - lo_area) / std::max(pace_.cum[k] - lo_area, 1e-300);
  return lo_tau + share * (pace_.tau[pace_.order[k]] - lo_tau);
}

void Simulation::pace_step(double dt) {
  // Per-step feedback on the speed scale: the tau still to cover over the time left, divided
  // by the efficiency, how much tau a second of scale really covers (eq 1's slope factor on a
  // curled sheet, the drive, the front's band holding times set at an older scale). The
  // efficiency is the ratio of decayed sums over a window of 15 % of the target, and the scale
  // moves by at most dt / (5 % of the target) a step: the front answers a change only after a
  // cell or two, and a faster loop oscillates (a lantern at 40 cells did, finishing 15 % early).
  if (!plan_cells_ || pace_.t0 < 0) return;
  if (pace_.stale) replan();
  if (pace_.order.empty()) return;
  constexpr double kMinScale = 1e-3, kMaxScale = 1e3;
  const double target = params_.finish_within;
  const double window = std::max(0.15 * target, 4.0 * dt);
  const double covered = tau_covered();
  if (pace_.has_prev && pace_.prev_dt > 0) {
    const double keep = std::exp(-pace_.prev_dt / window);
    pace_.covered = keep * pace_.covered + (covered - pace_.prev_tau);
    pace_.scaled = keep * pace_.scaled + speed_scale_ * pace_.prev_dt;
  }
  // A prior of a quarter window at efficiency 1, so the first steps' few cells do not rule.
  const double prior = 0.25 * window * speed_scale_;
  const double eta = std::clamp((pace_.covered + prior) / (pace_.scaled + prior), 0.05, 2.0);
  const double remaining = pace_.tau[pace_.order.back()] - covered;
  const double left = pace_.t0 + pace_.window - time_;
  if (remaining > 0) {
    double want = left > dt ? remaining / (left * eta) : kMaxScale;
    if (pace_.has_prev) {
      const double step = 1.0 + dt / (0.05 * target);
      want = std::clamp(want, speed_scale_ / step, speed_scale_ * step);
    }
    speed_scale_ = std::clamp(want, kMinScale, kMaxScale);
  }
  pace_.prev_tau = covered;
  pace_.prev_dt = dt;
  pace_.has_prev = true;
}

void Simulation::apply_maps(const RowMatX3i& faces, const CellMaps& maps) {
  auto read = [&](const Eigen::VectorXd& m, const char* name) {
    if (m.size() != vertices_.rows())
      throw std::invalid_argument(std::string(name) + ": one value per vertex expected (" +
                                  std::to_string(vertices_.rows()) + "), got " + std::to_string(m.size()));
    if (!m.allFinite() || (m.array() < 0).any())
      throw std::invalid_argument(std::string(name) + ": values must be finite and >= 0");
    return vertex_field_at_cells(*cells_, vertices_, faces, m, true);
  };
  // Fuel is how much there is to burn: the flame stays that much longer on a cell. The mass
  // (what the lattice carries) stays the material's, so a painted map changes the fire, not
  // the sheet's weight, and fuel 0 leaves no massless cells for the motion.
  if (maps.speed.size()) {
    const std::vector<double> s = read(maps.speed, "speed_map");
    for (int c = 0; c < cells_->size(); ++c) v_scale_[c] *= s[c];
  }
  if (maps.fuel.size()) {
    const std::vector<double> f = read(maps.fuel, "fuel_map");
    for (int c = 0; c < cells_->size(); ++c) {
      if (f[c] > 0) duration_[c] *= f[c];
      else v_scale_[c] = 0.0;  // nothing to burn: a firebreak
    }
  }
}

void Simulation::bind_cells() {
  grid_ = dynamic_cast<const GridCells*>(cells_.get());
  surface_ = dynamic_cast<const ShellCells*>(cells_.get());
  view_.position = [this](int c) { return cell_position(c); };
  view_.normal = [this](int c) { return cell_normal(c); };
  // Eq 1's slope is measured from the rest shape turned with its piece: on the grid the rest
  // plane's normal, on a surface the cell's own rest normal.
  view_.reference_normal = [this](int c) {
    const Eigen::Vector3d n0 = grid_ ? grid_->sheet().frame().n : cells_->rest_normal(c);
    return shell_ ? shell_->turned_rest_normal(c, n0) : n0;
  };
  law_.v = [this](int c) { return cell_speed(c); };
  law_.max_drive = params_.max_drive;
}

const Sheet& Simulation::sheet() const {
  if (!grid_) throw std::invalid_argument("sheet: this simulation's cells lie on the surface (geometry 'surface'), not on a grid");
  return grid_->sheet();
}

const SurfaceCells& Simulation::surface_cells() const {
  if (!surface_) throw std::invalid_argument("surface cells: this simulation's cells are a grid (geometry 'plane')");
  return surface_->surface();
}

ShellParams Simulation::shell_params() const {
  ShellParams sp;
  sp.lattice = params_.lattice;
  sp.lattice_thickness = params_.lattice_thickness;
  sp.crease_angle = params_.crease_angle;
  sp.has_floor = params_.has_floor;
  sp.floor_z = params_.floor_z;
  sp.ash_strength = params_.ash_strength;
  sp.mesh_tolerance = params_.mesh_tolerance;
  sp.imperfection = params_.imperfection;
  sp.seed = params_.seed;
  sp.dynamics = params_.dynamics;
  sp.particles = params_.particles;
  sp.bending = params_.bending;
  return sp;
}

void Simulation::build_locator() {
  // Grid cells only (surface cells are scanned): buckets are the lattice's control cells (a
  // cell moves with its quad's four couples), or blocks of kBlock x kBlock cells on a sheet
  // that never moves.
  if (!grid_) return;
  constexpr int kBlock = 4 * CellLocator::kBlock;
  const Sheet& sheet = grid_->sheet();
  const int N = sheet.cells(), nc = sheet.num_cells();
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
  locator_ = std::make_unique<CellLocator>(N, sheet.cell_rest(), sheet.inside(), bucket, buckets);
  locator_stale_ = shell_ != nullptr;
}

void Simulation::refresh_locator() const {
  if (!locator_stale_ || !locator_) return;
  RowMatX3 lo, hi;
  shell_->quad_displacement_bounds(lo, hi);
  locator_->set_displacement_bounds(lo, hi);
  locator_stale_ = false;
}

double Simulation::noise(int cell, std::uint64_t stream) const { return cells_->noise(cell, params_.seed, stream); }

Eigen::Vector3d Simulation::cell_position(int cell) const {
  return shell_ ? shell_->cell_position(cell) : cells_->rest(cell);
}

Eigen::Vector3d Simulation::cell_normal(int cell) const {
  if (!shell_) return cells_->rest_normal(cell);
  // On a control surface the layer's own normal there; on the grid, from the neighbours.
  if (shell_->control_surface()) return shell_->cell_normal(cell);
  return grid_->normal_from_neighbours(cell, view_);
}

double Simulation::grad2(int cell) const { return cells_->grad2(cell, view_); }

double Simulation::cell_speed(int cell) const {
  const double v0 = params_.v0 * v_scale_[cell];
  return std::max(params_.v_floor, 1.0 - params_.cv * grad2(cell)) * v0 * speed_scale_;
}

LocalSpeed Simulation::local_speed(int cell) const {
  if (!grid_) throw std::invalid_argument("local_speed: grid axes exist on geometry 'plane' only; use cell_speed");
  SpreadLaw law = law_;
  law.drive = drive();
  return grid_->local_speed(cell, law, view_);
}

Eigen::Vector3d Simulation::drive() const {
  return params_.climb * Eigen::Vector3d::UnitZ() + params_.wind_spread * wind_;
}

void Simulation::refresh_law() { law_.drive = drive(); }

int Simulation::ignite(const Eigen::Vector3d& point, double t, double radius) {
  std::vector<int> lit = cells_near(point, radius);
  lit.erase(std::remove_if(lit.begin(), lit.end(), [this](int c) { return is_firebreak(c); }), lit.end());
  // The front cannot rewrite cells it has already accepted, so an ignition time before the
  // last step is taken as that step's end: the fire starts now and catches up from there.
  const double t0 = std::max(t, cells_->front_time());
  refresh_law();
  if (radius == 0.0 && lit.size() == 1)
    cells_->ignite_point(lit[0], point - cell_position(lit[0]), t0, law_, view_);
  else
    for (int c : lit) cells_->ignite(c, t0, law_, view_);
  note_sources(lit, t0);
  return static_cast<int>(lit.size());
}

int Simulation::ignite_cells(const std::vector<int>& cells, double t) {
  const double t0 = std::max(t, cells_->front_time());
  refresh_law();
  std::vector<int> lit;
  for (int c : cells) {
    if (c < 0 || c >= cells_->size())
      throw std::invalid_argument("cells: index " + std::to_string(c) + " outside [0, " + std::to_string(cells_->size()) + ")");
    if (!cells_->inside()[c] || is_firebreak(c) || state_[c] != kUnburnt) continue;
    cells_->ignite(c, t0, law_, view_);
    lit.push_back(c);
  }
  note_sources(lit, t0);
  return static_cast<int>(lit.size());
}

int Simulation::ignite_near(const RowMatX3& points, double radius, double t) {
  if (!(radius >= 0) || !std::isfinite(radius)) throw std::invalid_argument("radius must be >= 0 and finite");
  if (points.rows() == 0) return 0;
  // Points in buckets of the radius (at least a cell's spacing): a cell looks in the 27 around it.
  const double h = std::max(radius, cells_->spacing());
  auto key = [h](const Eigen::Vector3d& p) {
    const Eigen::Vector3d q = (p / h).array().floor();
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(q.x()), static_cast<std::int64_t>(q.y()),
                                       static_cast<std::int64_t>(q.z())};
  };
  std::map<std::array<std::int64_t, 3>, std::vector<int>> buckets;
  for (Eigen::Index i = 0; i < points.rows(); ++i) buckets[key(points.row(i).transpose())].push_back(static_cast<int>(i));
  const double r2 = radius * radius;
  std::vector<int> near;
  for (int c = 0; c < cells_->size(); ++c) {
    if (!cells_->inside()[c] || state_[c] != kUnburnt || is_firebreak(c)) continue;
    const Eigen::Vector3d p = cell_position(c);
    const auto k = key(p);
    bool found = false;
    for (int dx = -1; dx <= 1 && !found; ++dx)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dz = -1; dz <= 1 && !found; ++dz) {
          const auto it = buckets.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == buckets.end()) continue;
          for (int i : it->second)
            if ((points.row(i).transpose() - p).squaredNorm() <= r2) {
              found = true;
              break;
            }
        }
    if (found) near.push_back(c);
  }
  return ignite_cells(near, t);
}

std::vector<double> Simulation::vertex_field(const Eigen::VectorXd& values) const {
  if (values.size() != vertices_.rows())
    throw std::invalid_argument("values: one per vertex expected (" + std::to_string(vertices_.rows()) + "), got " +
                                std::to_string(values.size()));
  return vertex_field_at_cells(*cells_, vertices_, faces_, values, false);
}

void Simulation::set_speed_scale(double s) {
  if (!(s > 0) || !std::isfinite(s)) throw std::invalid_argument("speed_scale must be > 0 and finite");
  speed_scale_ = s;
}

std::vector<int> Simulation::scan_cells_near(const Eigen::Vector3d& point, double radius, double* nearest_distance,
                                             int* nearest) const {
  // Every cell's position now: surface cells have no grid blocks to skip by (about 20 ns a cell).
  std::vector<int> within;
  *nearest = -1;
  *nearest_distance = kInf;
  for (int c = 0; c < cells_->size(); ++c) {
    const double d = (cell_position(c) - point).norm();
    if (d < *nearest_distance) {
      *nearest_distance = d;
      *nearest = c;
    }
    if (radius > 0 && d <= radius) within.push_back(c);
  }
  return within;
}

std::vector<int> Simulation::cells_near(const Eigen::Vector3d& point, double radius) const {
  CellLocator::Found found;
  if (locator_) {
    if (shell_) refresh_locator();
    found = locator_->find(point, radius, [this](int c) { return cell_position(c); });
  } else {
    found.within = scan_cells_near(point, radius, &found.distance, &found.nearest);
  }
  const int best = found.nearest;
  std::vector<int>& lit = found.within;
  const double reach = std::max({radius, cells_->reach(), 0.02 * std::sqrt(cells_->total_area())});
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
  std::unique_ptr<FireCells> cells;
  std::vector<std::uint8_t> state;
  std::vector<int> burning;
  std::vector<double> mass;
  Shell::Checkpoint shell;
  Pace pace;
  double speed_scale;
  std::vector<double> cell_temp;
  std::vector<std::uint8_t> piece_alight;
};

bool Simulation::step_may_throw() const {
  // Only an explicit integrator refuses a step (more than max_substeps needed); the implicit one
  // takes any step, so its frames never pay for a copy.
  return shell_ && !is_implicit(params_.dynamics.integrator);
}

Simulation::Saved Simulation::save() const {
  return Saved{time_, cells_->clone(), state_, burning_, mass_, shell_->checkpoint(), pace_, speed_scale_, cell_temp_, piece_alight_};
}

void Simulation::restore(Saved&& s) {
  time_ = s.time;
  cells_ = std::move(s.cells);
  bind_cells();
  state_ = std::move(s.state);
  burning_ = std::move(s.burning);
  mass_ = std::move(s.mass);
  shell_->rollback(std::move(s.shell));
  pace_ = std::move(s.pace);
  speed_scale_ = s.speed_scale;
  cell_temp_ = std::move(s.cell_temp);
  piece_alight_ = std::move(s.piece_alight);
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
  {
    PhaseTimer timer(times_, Phase::FireFront);
    pace_step(dt);
    refresh_law();
    for (int c : cells_->advance(t_end, law_, view_)) {
      if (state_[c] != kUnburnt) continue;
      state_[c] = kBurning;
      burning_.push_back(c);
    }
  }
  time_ = t_end;
  {
    PhaseTimer timer(times_, Phase::Cells);
    retire_burnt();
  }
  if (shell_) step_shell(dt);
  locator_stale_ = shell_ != nullptr;
  PhaseTimer timer(times_, Phase::Cells);
  heat_ignite(dt);
}

PhaseTimes Simulation::phase_times() const {
  PhaseTimes t = times_;
  if (shell_)
    for (std::size_t p = 0; p < kPhases; ++p) t.seconds[p] += shell_->phase_times().seconds[p];
  return t;
}

void Simulation::retire_burnt() {
  const auto& arrival = cells_->arrival();
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
  std::vector<double> t(cells_->arrival());
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
  out.clear();
  for (int c : burning_)
    if (cells_->on_fringe(c, state_)) out.push_back(c);
  std::sort(out.begin(), out.end());
}

std::vector<double> Simulation::cell_char() const {
  const auto& arrival = cells_->arrival();
  std::vector<double> ch(arrival.size(), 0.0);
  for (std::size_t c = 0; c < ch.size(); ++c)
    if (state_[c] != kUnburnt) ch[c] = std::clamp((time_ - arrival[c]) / duration_[c], 0.0, 1.0);
  return ch;
}

RowMatX3 Simulation::cell_positions() const {
  RowMatX3 p(cells_->size(), 3);
  for (int c = 0; c < cells_->size(); ++c) p.row(c) = cell_position(c).transpose();
  return p;
}

RowMatX3 Simulation::vertex_positions() const {
  if (!shell_) return vertices_;
  RowMatX3 out;
  shell_->vertex_positions(out);
  return out;
}

void Simulation::vertex_positions_into(Eigen::Ref<RowMatX3> out) const {
  if (out.rows() != vertices_.rows())
    throw std::invalid_argument("out: expected " + std::to_string(vertices_.rows()) + " rows (one per vertex), got " +
                                std::to_string(out.rows()));
  if (!shell_) {
    out = vertices_;
    return;
  }
  shell_->vertex_positions_into(out);
}

RowMatX3 Simulation::mesh_points(const Eigen::Ref<const RowMatXi>& idx, const Eigen::Ref<const RowMatXd>& w) const {
  if (idx.rows() != w.rows() || idx.cols() != w.cols())
    throw std::invalid_argument("weights: expected the shape of vertices (" + std::to_string(idx.rows()) + ", " +
                                std::to_string(idx.cols()) + "), got (" + std::to_string(w.rows()) + ", " +
                                std::to_string(w.cols()) + ")");
  const long n = static_cast<long>(vertices_.rows());
  for (Eigen::Index i = 0; i < idx.size(); ++i)
    if (idx.data()[i] < 0 || idx.data()[i] >= n)
      throw std::invalid_argument("vertices: indices must be in [0, " + std::to_string(n) + "), got " +
                                  std::to_string(idx.data()[i]));
  RowMatX3 out;
  if (shell_) {
    shell_->mesh_points(idx, w, out);
    return out;
  }
  out = RowMatX3::Zero(idx.rows(), 3);
  for (Eigen::Index i = 0; i < idx.rows(); ++i)
    for (Eigen::Index k = 0; k < idx.cols(); ++k) out.row(i) += w(i, k) * vertices_.row(idx(i, k));
  return out;
}

Eigen::VectorXd Simulation::vertex_char() const {
  const std::vector<double> ch = cell_char();
  Eigen::VectorXd out(vertices_.rows());
  cells_->cells_to_vertices(ch.data(), out.data());
  return out;
}

Eigen::VectorXd Simulation::vertex_ignition_times() const {
  const std::vector<double> t = ignition_times();
  const auto& vc = cells_->vertex_cell();
  Eigen::VectorXd out(vc.size());
  for (std::size_t i = 0; i < vc.size(); ++i) out[i] = t[vc[i]];
  return out;
}

Eigen::VectorXd Simulation::vertex_burnout_times() const {
  Eigen::VectorXd out = vertex_ignition_times();
  const auto& vc = cells_->vertex_cell();
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
  show_floor_in_dynamics();
}

void Simulation::show_floor_in_dynamics() {
  // The floor is the simulation's (the shell lowers it by half the lattice's thickness for the
  // motion): the motion's copy of it shows the one in force, so params() reads as it acts.
  params_.dynamics.has_floor = params_.has_floor;
  params_.dynamics.floor_z = params_.floor_z;
}

const RowMatX3& Simulation::lattice_positions() const {
  if (!shell_) throw std::invalid_argument("lattice: this simulation has no shell");
  return shell_->lattice().positions();
}

double Simulation::flame_side(int cell) const {
  // Flames sit on the upper face of a burning cell; on a near-vertical cell the face is a
  // seeded coin toss, which is what lets a hanging sheet crumple both ways. On a closed
  // piece, its outside (find_outsides).
  if (!piece_outside_.empty() && piece_outside_[piece_[cell]] != 0.0) return piece_outside_[piece_[cell]];
  const double nz = cell_normal(cell).z();
  if (std::abs(nz) > 0.2) return nz > 0 ? 1.0 : -1.0;
  return seeded_uniform(params_.seed, 3, static_cast<std::uint64_t>(cell)) >= 0 ? 1.0 : -1.0;
}

void Simulation::gather_shell_sources() {
  // Emitters: the fringe (paper §3.1), each a cell's worth of front length. Ignition points
  // (eq 3): the burning cells, on their flame face.
  fringe_into(fringe_buf_);
  const Eigen::Index k = static_cast<Eigen::Index>(fringe_buf_.size());
  // The fire sources (a candle) after the fringe, so the fringe's emitters keep their numbers
  // (their random draws) and a simulation without sources is unchanged.
  const Eigen::Index ks = source_pos_.rows();
  emit_pos_.resize(k + ks, 3);
  emit_normal_.resize(k + ks, 3);
  emit_len_.setConstant(k + ks, cells_->spacing());
  emit_side_.setZero(k + ks);  // 0: the particles' own rule (the upper side)
  for (Eigen::Index e = 0; e < k; ++e) {
    emit_pos_.row(e) = cell_position(fringe_buf_[e]).transpose();
    emit_normal_.row(e) = cell_normal(fringe_buf_[e]).transpose();
    if (!piece_outside_.empty()) emit_side_[e] = piece_outside_[piece_[fringe_buf_[e]]];
  }
  for (Eigen::Index e = 0; e < ks; ++e) {
    emit_pos_.row(k + e) = source_pos_.row(e);
    emit_normal_.row(k + e) = Eigen::RowVector3d::UnitZ();  // a flame burns upward
    emit_len_[k + e] = source_len_[e];
  }
  const double half = 0.5 * shell_->thickness();
  ignition_pts_.resize(static_cast<Eigen::Index>(burning_.size()), 3);
  for (std::size_t b = 0; b < burning_.size(); ++b) {
    const int c = burning_[b];
    ignition_pts_.row(b) = (cell_position(c) + half * flame_side(c) * cell_normal(c)).transpose();
  }
}

void Simulation::step_shell(double dt) {
  {
    PhaseTimer timer(times_, Phase::Sources);
    gather_shell_sources();
  }
  shell_->step(dt, ShellSources{&emit_pos_, &emit_normal_, &emit_len_, &ignition_pts_, &emit_side_}, wind_);
}

}  // namespace thinburn
