// The shell half of the model (paper §4): the FFD lattice draped over the sheet, the cells'
// mass mapped onto it, fire particles, heat and pyrolysis, the rotation D and the motion.
#include "shell.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

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

// The layer's default thickness: a quarter of the couples' spacing, at most kMaxThickness. The
// layer's bending stiffness grows as its thickness squared (the top and bottom springs pull
// opposite ways); at 0.25 of a 33 cm spacing a 1.4 m paper curtain pinned along its top stood
// upright above its pins after the wind dropped (repro r10); at 1 cm it hangs again.
constexpr double kMaxThickness = 0.01;  // m
double default_thickness(double spacing) { return std::min(0.25 * spacing, kMaxThickness); }

// A chosen control surface follows the curve down to kMaxRefine times the grid's spacing. It
// carries the mesh in its layer when the 99th percentile of its vertices' offsets from the
// interpolated mid-surface is at most kLayerFit half-thicknesses; else it gets kFitStep times
// finer, down to kMaxFitRefine times the grid's spacing (at 64 cells a pleated curtain stopped
// at fit 1.47 with 4 times and strained 14 %).
constexpr double kLayerFit = 0.5, kFitStep = 0.75, kMaxRefine = 4.0, kMaxFitRefine = 8.0;
constexpr int kFitPasses = 8;

// The 99th percentile over the embedded points of |offset| / (thickness / 2).
double embedding_fit(const SurfaceEmbedding& e, double thickness) {
  if (e.size() == 0 || !(thickness > 0)) return 0.0;
  std::vector<double> r(e.size());
  for (Eigen::Index i = 0; i < e.size(); ++i) r[i] = std::abs(e.offset(i)) / (0.5 * thickness);
  const std::size_t at = static_cast<std::size_t>(0.99 * double(r.size() - 1));
  std::nth_element(r.begin(), r.begin() + at, r.end());
  return r[at];
}

}  // namespace

const std::vector<param::Field<ShellParams>>& ShellParams::fields() {
  using P = ShellParams;
  using namespace param;
  static const std::vector<Field<P>> table = {
      field("lattice", &P::lattice, at_least(0), "M couples per side (0: chosen from the sheet and its cells)"),
      field("lattice_thickness", &P::lattice_thickness, at_least(0), "m between a couple's two vertices (0: chosen)"),
      field("crease_angle", &P::crease_angle, within(0, 180),
            "degrees: a curved shell's mesh edges turning by more are creases, hinges (180: none)"),
      field("has_floor", &P::has_floor, "a horizontal floor under the sheet"),
      field("floor_z", &P::floor_z, "m: the floor's height"),
      field("ash_strength", &P::ash_strength, within(0, 1), "share of the springs' stiffness burnt sheet keeps"),
      field("mesh_tolerance", &P::mesh_tolerance, within(0, 1),
            "share of the sheet's size a couple drifts before its mesh vertices are redone (0: exact)"),
      field("imperfection", &P::imperfection, within(0, 0.1),
            "share of the sheet's size it starts bowed by along its normals (0: perfectly flat)"),
      field("seed", &P::seed, "seeds the particles' random stream"),
  };
  return table;
}

void validate(const ShellParams& p) {
  param::check_all(ShellParams::fields(), p);
  // 1 couple per side has no springs between couples (the table cannot say "0 or >= 2").
  if (p.lattice == 1) throw std::invalid_argument("lattice must be 0 (chosen) or >= 2, got 1");
  validate(p.dynamics);
  validate(p.particles);
  validate(p.bending);
}

Shell::Shell(const Sheet& sheet, const ShellParams& params, const std::vector<double>& cell_mass,
             const std::vector<std::uint8_t>& pinned)
    : sheet_(&sheet), params_(params) {
  validate(params_);
  const int N = sheet.cells();
  M_ = params_.lattice > 0 ? params_.lattice : choose_lattice(N, sheet.size_u(), sheet.size_v());
  if (M_ < 2) throw std::invalid_argument("lattice must be >= 2");
  const double spacing = std::min(sheet.size_u(), sheet.size_v()) / (M_ - 1);
  thickness_ = params_.lattice_thickness > 0 ? params_.lattice_thickness : default_thickness(spacing);
  lattice_ = std::make_unique<FfdLattice>(M_, drape());

  const RowMatX2& vp = sheet.vertex_param();
  RowMatX3 coords(vp.rows(), 3);
  for (Eigen::Index i = 0; i < vp.rows(); ++i) {
    const Eigen::Vector2d st = sheet.lattice_st(vp(i, 0), vp(i, 1), M_);
    coords.row(i) << st.x(), st.y(), 0.5;
  }
  // A flat sheet takes the quadratic B-spline, C1 across control cells: the trilinear map
  // kinks there, and the A4 demo's faces away from the fire met at up to 10.5 degrees (silk
  // held at its corners: 28.6), 1.35 (3.4) with the spline (scripts/shell_smoothness.py;
  // issue #12's facets). A sheet that is not flat on its grid (geometry="plane" over a folded
  // sheet's UV map) keeps the trilinear map: the spline approximates rather than interpolates,
  // and it would round the fold off (its edges shrank to 0.76 in a free fall).
  mesh_interp_ = rest_is_flat() ? LatticeInterp::QuadraticBSpline : LatticeInterp::Trilinear;
  vertex_embedding_ = lattice_->embed(coords, sheet.vertices(), mesh_interp_);
  // Relative to the sheet, not in metres: what a picture of it can show scales with its size
  // (a camera frames the sheet), and the model takes sheets from micrometres to kilometres.
  const double mesh_tol = params_.mesh_tolerance * std::max(sheet.size_u(), sheet.size_v());
  mesh_deform_ = std::make_unique<CachedDeform>(vertex_embedding_, lattice_->couples(), mesh_tol);
  if (mesh_interp_ == LatticeInterp::QuadraticBSpline)
    fold_blend_ = std::make_unique<FoldBlend>(lattice_->embed(coords, sheet.vertices(), LatticeInterp::Trilinear));
  cell_area_.assign(N * N, sheet.du() * sheet.dv());
  // Eq 3 sums over the ignition points, the burning cells: the same fire at twice the grid
  // resolution has four times the points. Each cell counts as its share of a cell of the
  // paper's 128 x 128 grid, so pyrolysis (and the bend) does not depend on N, and N = 128
  // is the paper's Cp.
  const double per_paper_cell = static_cast<double>(kPaperCells) / N;
  finish(cell_mass, N * N, sheet.inside(), grid_topology(M_), per_paper_cell * per_paper_cell);
  find_pieces();
  if (!pinned.empty()) pin(pinned);
  bow();
  if (params_.has_floor) set_centre_floor();
}

Shell::Shell(const SurfaceCells& cells, const RowMatX3& vertices, const RowMatX3i& faces,
             const ShellParams& params, const std::vector<double>& cell_mass,
             const std::vector<std::uint8_t>& pinned)
    : params_(params) {
  validate(params_);
  // The grid's choice (one couple per 16 cells, none finer than 2 cm, 4..65 per side) with
  // sqrt(area) for the side; an explicit lattice counts couples along sqrt(area).
  const double side = std::sqrt(cells.total_area());
  double spacing = params_.lattice > 0 ? side / (params_.lattice - 1)
                                       : std::clamp(std::max(16.0 * cells.spacing(), 0.02), side / 64.0, side / 3.0);
  thickness_ = params_.lattice_thickness > 0 ? params_.lattice_thickness : default_thickness(spacing);
  // A chosen lattice that leaves a piece without a triangulated control surface (a small piece,
  // a mesh of two triangles) gets finer until it has one; an explicit one is refused by name.
  constexpr int kFinerTries = 6;
  for (int attempt = 0;; ++attempt) {
    try {
      control_ = std::make_unique<ControlSurface>(vertices, faces, spacing, thickness_, params_.crease_angle);
      break;
    } catch (const std::invalid_argument& e) {
      if (params_.lattice > 0 || attempt == kFinerTries || std::string(e.what()).rfind("lattice", 0) != 0) throw;
      spacing *= 0.6;
      if (params_.lattice_thickness <= 0) thickness_ = default_thickness(spacing);
    }
  }
  // A chosen lattice also follows the curve: at most kMaxTurn radians between neighbouring
  // couples' normals at half the couples (a lantern of r = 10 cm gets about 16 couples round,
  // not 6; a crease, a few edges, does not refine: at the 0.9 quantile a folded letter got 1024
  // couples and ran at 8 frames/s), at most kMaxRefine times finer than the grid's choice.
  constexpr double kMaxTurn = 0.4, kCurvedEdges = 0.5;
  const double coarsest = spacing;
  auto rebuild = [&](double s) {
    spacing = s;
    thickness_ = params_.lattice_thickness > 0 ? params_.lattice_thickness : default_thickness(spacing);
    control_ = std::make_unique<ControlSurface>(vertices, faces, spacing, thickness_, params_.crease_angle);
  };
  auto follow_curve = [&](double finest) {
    for (int pass = 0; params_.lattice == 0 && pass < 3; ++pass) {
      const double kappa = control_->edge_curvature(kCurvedEdges);
      if (!(kappa * spacing > 1.15 * kMaxTurn) || spacing <= finest * 1.0001) break;
      rebuild(std::max(kMaxTurn / kappa, finest));
    }
  };
  follow_curve(coarsest / kMaxRefine);
  // And it carries the mesh in its layer: finer while the mesh's detail (pleats, waves) lies
  // farther from the control surface than half the layer's thickness at more than 1 % of its
  // vertices. Detail the lattice cannot follow rides at its offset along the layer's normal,
  // and bending the layer by a curvature k stretches it by k times that offset: a curtain with
  // 2 cm pleats 20 cm apart hung with 12.5 % strain (p99) on 64 couples (docs/lattice.md).
  std::vector<int> vertex_seed, cell_seed;
  bool refined = false;
  for (int pass = 0;; ++pass) {
    piece_seeds(cells, faces, &vertex_seed, &cell_seed);
    surface_vertices_ = control_->embed(vertices, vertex_seed);
    layer_fit_ = embedding_fit(surface_vertices_, thickness_);
    if (params_.lattice > 0 || pass == kFitPasses || !(layer_fit_ > kLayerFit) ||
        spacing <= coarsest / kMaxFitRefine * 1.0001) {
      if (!refined) break;
      // Detail the coarse lattice could not see (pleats between couples) shows its curvature
      // once the layer follows it: follow that too.
      refined = false;
      const double before = spacing;
      follow_curve(coarsest / kMaxFitRefine);
      if (spacing == before) break;
      continue;
    }
    rebuild(std::max(kFitStep * spacing, coarsest / kMaxFitRefine));
    refined = true;
  }
  vertex_seed_ = vertex_seed;
  lattice_ = std::make_unique<FfdLattice>(FfdLattice::on_surface(control_->couples(), control_->rest()));
  RowMatX3 centres(cells.size(), 3);
  for (int c = 0; c < cells.size(); ++c) centres.row(c) = cells.positions()[c].transpose();
  surface_cells_ = control_->embed(centres, cell_seed);
  cell_area_ = cells.areas();
  const double paper_cell = cells.total_area() / (kPaperCells * kPaperCells);
  const double per_paper_cell = (cells.total_area() / cells.size()) / paper_cell;
  finish(cell_mass, cells.size(), std::vector<std::uint8_t>(cells.size(), 1), control_->topology(), per_paper_cell);
  find_pieces();
  if (params_.has_floor) set_floor_offsets();
  if (!pinned.empty()) pin(pinned);
  bow();
}

namespace {

// Up to k of the given points (rows of p), each the farthest from those picked before
// (farthest-point sampling from the first): a cloud's extremes come first.
std::vector<int> spread_out(const RowMatX3& p, const std::vector<int>& points, int k) {
  if (static_cast<int>(points.size()) <= k) return points;
  std::vector<int> kept{points[0]};
  std::vector<double> gap(points.size(), std::numeric_limits<double>::infinity());
  while (static_cast<int>(kept.size()) < k) {
    std::size_t far = 0;
    for (std::size_t j = 0; j < points.size(); ++j) {
      gap[j] = std::min(gap[j], (p.row(points[j]) - p.row(kept.back())).squaredNorm());
      if (gap[j] > gap[far]) far = j;
    }
    kept.push_back(points[far]);
  }
  return kept;
}

}  // namespace

void Shell::set_floor_offsets() {
  // A control vertex touches the floor when the lowest mesh point it carries a fair share of
  // does: a lantern's lowest couples sit above its rim. Which point is lowest depends on how
  // the shell lies, so the dynamics take the points' heights as they are (FloorSupport): on the
  // rest pose's heights a paper sphere rolling in a 3 m/s wind floated 12-39 mm above its table.
  // A couple's points are those it moves most (its MLS weight at least kCarried, or the
  // largest of the point's): lifting the couple lifts them. On the points it merely shared
  // (window share over 0.1, MLS weight small or negative) the floor kept lifting couples that
  // hardly moved the point, and a paper sphere at rest under the symplectic integrator hopped
  // 30 mm. Of a couple's points, kFloorPoints spread over its window stand for them all: the
  // lowest of all 470 or so was 18 ms a frame on a 16k-vertex lantern (2 ms without).
  constexpr double kCarried = 0.3;
  constexpr int kFloorPoints = 16;
  constexpr int S = SurfaceEmbedding::kStencil;
  const int C = lattice_->couples();
  const RowMatX3& rest = lattice_->rest();
  std::vector<std::vector<int>> by_couple(C);
  for (Eigen::Index i = 0; i < surface_vertices_.size(); ++i) {
    const double* w = surface_vertices_.weight.data() + std::size_t(i) * S;
    const int owner = static_cast<int>(std::max_element(w, w + S) - w);
    for (int q = 0; q < S; ++q)
      if (q == owner || w[q] >= kCarried)
        by_couple[surface_vertices_.couple[std::size_t(i) * S + q]].push_back(static_cast<int>(i));
  }
  std::vector<int> start(1, 0), points;
  Eigen::VectorXd reach = Eigen::VectorXd::Zero(C);
  for (int c = 0; c < C; ++c) {
    const Eigen::RowVector3d mid = 0.5 * (rest.row(2 * c) + rest.row(2 * c + 1));
    for (int i : by_couple[c]) reach[c] = std::max(reach[c], (surface_vertices_.rest.row(i) - mid).norm());
    const std::vector<int> kept = spread_out(surface_vertices_.rest, by_couple[c], kFloorPoints);
    points.insert(points.end(), kept.begin(), kept.end());
    start.push_back(static_cast<int>(points.size()));
  }
  // The dynamics live no longer than the control surface and the embedding they read.
  auto height = [this](const RowMatX3& x, int i) { return control_->point(surface_vertices_, i, x).z(); };
  dynamics_->set_floor_support(
      std::make_unique<FloorSupport>(std::move(start), std::move(points), std::move(reach), height, 0.5 * thickness_));
}

void Shell::set_centre_floor() {
  // A flat sheet's mesh lies in its lattice's mid-surface, a convex combination of the couples'
  // centres, so a control vertex touches the floor when its couple's centre does: its floor
  // follows the couple's tilt (FloorSupport with no mesh points). A floor half a thickness
  // under the sheet's for every vertex held a lying sheet right, but a sheet standing on its
  // edge sank half a thickness into it and the mesh's clamp to the floor crushed its bottom
  // 5 mm flat (a 20 cm sheet: its bottom-row edges 100 % short).
  const int C = lattice_->couples();
  dynamics_->set_floor_support(std::make_unique<FloorSupport>(std::vector<int>(C + 1, 0), std::vector<int>{},
                                                              Eigen::VectorXd::Zero(C), nullptr, 0.5 * thickness_));
}

namespace {

struct UnionFind {
  std::vector<int> up;
  explicit UnionFind(int n) : up(n) { std::iota(up.begin(), up.end(), 0); }
  int root(int a) {
    while (up[a] != a) a = up[a] = up[up[a]];
    return a;
  }
  void join(int a, int b) { up[root(a)] = root(b); }
};

// The corner of a vertex's interpolation triangle with the largest weight: a cell of its region.
int main_cell(const SurfaceCells& s, int vertex) {
  const auto& w = s.vertex_weights()[vertex];
  const int k = w[1] > w[0] ? (w[2] > w[1] ? 2 : 1) : (w[2] > w[0] ? 2 : 0);
  return s.vertex_cells()[vertex][k];
}

}  // namespace

void Shell::piece_seeds(const SurfaceCells& cells, const RowMatX3i& faces, std::vector<int>* vertex_seed,
                        std::vector<int>* cell_seed) const {
  // Which piece of the shell (a sheet of a stack) each input vertex, fire cell and couple is on:
  // one union-find over all three, joined along the mesh's faces, the cells' and the couples'
  // neighbour graphs and each vertex's interpolation corners (which weld UV seams). A vertex's
  // seed is its own region's couple; a fire cell's, the nearest couple of its own piece.
  const SurfaceCells& coarse = control_->cells();
  const int nv = static_cast<int>(cells.vertex_cells().size()), nf = cells.size(), nc = coarse.size();
  UnionFind uf(nv + nf + nc);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int k = 0; k < 3; ++k) uf.join(faces(f, k), faces(f, (k + 1) % 3));
  for (int v = 0; v < nv; ++v)
    for (int k = 0; k < 3; ++k) {
      uf.join(v, nv + cells.vertex_cells()[v][k]);
      uf.join(v, nv + nf + coarse.vertex_cells()[v][k]);
    }
  for (int c = 0; c < nf; ++c)
    for (int q = cells.nbr_offset()[c]; q < cells.nbr_offset()[c + 1]; ++q) uf.join(nv + c, nv + cells.nbr_index()[q]);
  for (int c = 0; c < nc; ++c)
    for (int q = coarse.nbr_offset()[c]; q < coarse.nbr_offset()[c + 1]; ++q)
      uf.join(nv + nf + c, nv + nf + coarse.nbr_index()[q]);
  vertex_seed->resize(nv);
  for (int v = 0; v < nv; ++v) (*vertex_seed)[v] = main_cell(coarse, v);
  std::vector<std::vector<int>> by_piece(nv + nf + nc);
  for (int c = 0; c < nc; ++c) by_piece[uf.root(nv + nf + c)].push_back(c);
  cell_seed->resize(nf);
  for (int c = 0; c < nf; ++c) {
    const Eigen::Vector3d p = cells.positions()[c];
    int best = coarse.nearest(p);
    const int piece = uf.root(nv + c);
    if (uf.root(nv + nf + best) != piece) {  // the nearest couple is on another sheet
      double d_best = std::numeric_limits<double>::infinity();
      for (int k : by_piece[piece]) {
        const double d = (coarse.positions()[k] - p).squaredNorm();
        if (d < d_best) d_best = d, best = k;
      }
    }
    (*cell_seed)[c] = best;
  }
}

void Shell::finish(const std::vector<double>& cell_mass, int num_cells, const std::vector<std::uint8_t>& inside,
                   const LatticeTopology& topology, double per_paper_cell) {
  // Cell masses and areas onto the couples, half to each layer.
  const int nv = lattice_->size();
  control_mass_ = Eigen::VectorXd::Zero(nv);
  control_area_ = Eigen::VectorXd::Zero(nv);
  burnt_area_ = Eigen::VectorXd::Zero(nv);
  for (int c = 0; c < num_cells; ++c) {
    if (!inside[c]) continue;
    add_cell_mass(c, cell_mass[c]);
    add_cell_area(c, control_area_);
  }

  DynamicsParams dp = params_.dynamics;
  // The mid-surface rests on the floor, so the bottom layer is held half a thickness lower.
  dp.has_floor = params_.has_floor;
  dp.floor_z = params_.floor_z - 0.5 * thickness_;
  dynamics_ = std::make_unique<LatticeDynamics>(*lattice_, dp, topology);
  mass_dirty_ = true;
  dynamics_->set_areas(control_area_);

  ParticleParams pp = params_.particles;
  pp.seed = params_.seed ^ 0x5bd1e995ULL;
  particles_ = std::make_unique<ParticleSystem>(pp);
  BendingParams bp = params_.bending;
  bp.cp *= per_paper_cell;
  bending_ = std::make_unique<Bending>(lattice_->couples(), bp);
}

void Shell::pin(const std::vector<std::uint8_t>& pinned) {
  // A pinned vertex holds every couple its position depends on, both layers, so it stays where
  // it is: on a control surface every couple in its window (holding only those that carry
  // more than 5 % of it let a pleated curtain's pinned top move 5.3 mm in a 2 m/s wind).
  std::vector<std::uint8_t> held(lattice_->size(), 0);
  if (control_) {
    constexpr int S = SurfaceEmbedding::kStencil;
    for (std::size_t i = 0; i < pinned.size(); ++i)
      for (int q = 0; pinned[i] && q < S; ++q)
        if (surface_vertices_.share[i * S + q] > 0.0) {
          const int c = surface_vertices_.couple[i * S + q];
          held[2 * c] = held[2 * c + 1] = 1;
        }
    dynamics_->set_pinned(held);
    return;
  }
  const RowMatX2& vp = sheet_->vertex_param();
  for (Eigen::Index i = 0; i < vp.rows(); ++i) {
    if (!pinned[i]) continue;
    int cp[4];
    double w[4];
    const Eigen::Vector2d st = sheet_->lattice_st(vp(i, 0), vp(i, 1), M_);
    bilinear_couples(st.x(), st.y(), cp, w);
    for (int k = 0; k < 4; ++k)
      if (w[k] > 1e-12) held[2 * cp[k]] = held[2 * cp[k] + 1] = 1;
  }
  dynamics_->set_pinned(held);
}

void Shell::bow() {
  // A flat sheet starts as a dome along its normal (bottom -> top): imperfection x its size at
  // its centroid, 0 at its farthest couple, times the share of gravity in its plane,
  // 1 - |n . g| / |g|. The rest lengths stay flat, so a sheet its weight leaves stable springs
  // back flat, and one its weight loads past buckling (a tall sheet pinned along its bottom:
  // Greenhill's column, scripts/greenhill.py) falls, as a real sheet does; without it a 1.4 m
  // paper sheet stood in its plane for ever (issue #12). Across its plane the weight itself
  // bends a sheet far more than L/1000 (a lying sheet keeps its exact start); a curved or folded
  // shell is not symmetric about a plane, its shape is its own imperfection.
  const Eigen::Vector3d g = params_.dynamics.gravity;
  if (!(params_.imperfection > 0) || !(g.norm() > 0) || !rest_is_flat()) return;
  const RowMatX3& r = lattice_->rest();
  const Eigen::RowVector3d n = (r.row(1) - r.row(0)).normalized();
  const double in_plane = 1.0 - std::abs(n.dot(g.normalized().transpose()));
  const int C = lattice_->couples();
  Eigen::RowVector3d centre = Eigen::RowVector3d::Zero();
  for (int c = 0; c < C; ++c) centre += 0.5 * (r.row(2 * c) + r.row(2 * c + 1));
  centre /= C;
  double R2 = 0;
  for (int c = 0; c < C; ++c) R2 = std::max(R2, (0.5 * (r.row(2 * c) + r.row(2 * c + 1)) - centre).squaredNorm());
  const double height = params_.imperfection * 2.0 * std::sqrt(R2) * in_plane;
  if (!(height > 0)) return;
  const std::vector<std::uint8_t>& pinned = dynamics_->pinned();
  RowMatX3 x = lattice_->positions();
  for (int c = 0; c < C; ++c) {
    if (pinned[2 * c] || pinned[2 * c + 1]) continue;
    const Eigen::RowVector3d mid = 0.5 * (r.row(2 * c) + r.row(2 * c + 1));
    const Eigen::RowVector3d d = height * (1.0 - (mid - centre).squaredNorm() / R2) * n;
    x.row(2 * c) += d;
    x.row(2 * c + 1) += d;
  }
  dynamics_->set_state(x, RowMatX3::Zero(x.rows(), 3));
}

bool Shell::rest_is_flat() const {
  // Every couple's rest direction (bottom -> top) along the first one's, to rounding.
  const RowMatX3& r = lattice_->rest();
  const Eigen::Vector3d n0 = (r.row(1) - r.row(0)).normalized().transpose();
  for (Eigen::Index c = 0; 2 * c + 1 < r.rows(); ++c)
    if ((r.row(2 * c + 1) - r.row(2 * c)).normalized().dot(n0.transpose()) < 1.0 - 1e-9) return false;
  return true;
}

void Shell::bilinear_couples(double s, double t, int* couple, double* w) const {
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

RowMatX3 Shell::drape() const {
  // Couple (i, j) sits on the rest surface at parameter (u_j, v_i), its two vertices half the
  // thickness either side along the surface normal; the cell grid is interpolated (and
  // extrapolated half a cell at the border) to find that surface point.
  const int N = sheet_->cells();
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
      const double fr = i * sheet_->size_v() / (M_ - 1) / sheet_->dv() - 0.5;
      const double fc = j * sheet_->size_u() / (M_ - 1) / sheet_->du() - 0.5;
      const Eigen::Vector3d mid = sample(sheet_->cell_rest(), fr, fc);
      Eigen::Vector3d n = sample(sheet_->cell_rest_normal(), fr, fc);
      n = n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : sheet_->frame().n;
      rest.row((i * M_ + j) * 2 + 0) = (mid - 0.5 * thickness_ * n).transpose();
      rest.row((i * M_ + j) * 2 + 1) = (mid + 0.5 * thickness_ * n).transpose();
    }
  return rest;
}

void Shell::set_colliders(std::shared_ptr<const Colliders> c, double margin, int samples) {
  if (samples < 0 || samples > kMaxContactSamples)
    throw std::invalid_argument("samples must be in [0, " + std::to_string(kMaxContactSamples) +
                                "] per control cell side, got " + std::to_string(samples));
  // Built only with colliders: a scene without any pays nothing.
  ContactSamples s;
  if (c && samples > 0) s = control_ ? surface_contact_samples(samples) : contact_samples(samples);
  if (fold_blend_) {
    // The samples ride the spline (contact_samples): near a collider the mesh keeps the
    // spline's points (FoldBlend::set_keep_out).
    std::lock_guard<std::mutex> lock(mesh_mutex_);
    fold_blend_->set_keep_out(s.vertex.empty() ? nullptr : c, margin);
  }
  dynamics_->set_colliders(std::move(c), margin, std::move(s));
}

ContactSamples Shell::surface_contact_samples(int per_cell) const {
  // A curved shell's samples: mesh vertices about spacing / per_cell apart, each taken with its
  // own embedding, so a sample is the mesh there. The embedding is the mid-surface's MLS over
  // the couples plus the rest offset along the layer's normal (the sag of a curve between
  // couples); that normal turns with the layer, which is not linear in the control vertices. The
  // couple's axis (top - bottom) is: with n = sum w_c axis_c, the point at rest is
  // mid + alpha n exactly, alpha = offset / |n|, and the sample sum_c w_c ((1/2 - alpha) bottom_c
  // + (1/2 + alpha) top_c) is linear and follows the layer's turn to first order.
  const SurfaceEmbedding& e = surface_vertices_;
  const int K = SurfaceEmbedding::kStencil;
  const double spacing = control_->spacing() / per_cell;
  const std::vector<int> keep = spread_points(e.rest, spacing);
  const RowMatX3& rest = control_->rest();
  ContactSamples out;
  out.stencil = 2 * K;
  out.spacing = spacing;
  out.group.push_back(0);
  for (int i : keep) {
    const std::size_t at = std::size_t(i) * K;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (int k = 0; k < K; ++k)
      n += e.weight[at + k] * (rest.row(2 * e.couple[at + k] + 1) - rest.row(2 * e.couple[at + k])).transpose();
    const double alpha = n.norm() > 0.0 ? e.offset(i) / n.norm() : 0.0;
    double spread = 0.0;
    for (int k = 0; k < K; ++k) {
      const int c = e.couple[at + k];
      const double wb = e.weight[at + k] * (0.5 - alpha), wt = e.weight[at + k] * (0.5 + alpha);
      out.vertex.insert(out.vertex.end(), {2 * c, 2 * c + 1});
      out.weight.insert(out.weight.end(), {wb, wt});
      spread += std::abs(wb) + std::abs(wt);
    }
    out.spread = std::max(out.spread, spread);
    out.group.push_back(out.size());  // a group each: no two samples share their couples
  }
  return out;
}

std::vector<int> Shell::spread_points(const RowMatX3& points, double spacing) {
  // Greedy, in the points' order: a point is kept when no kept point lies within `spacing` of
  // it (found in a hash of spacing-sized cells), so the kept points cover the shell about
  // `spacing` apart, with none closer.
  std::map<std::array<long, 3>, std::vector<int>> cells;
  std::vector<int> keep;
  const auto cell_of = [&](const Eigen::Vector3d& p) {
    return std::array<long, 3>{static_cast<long>(std::floor(p.x() / spacing)),
                               static_cast<long>(std::floor(p.y() / spacing)),
                               static_cast<long>(std::floor(p.z() / spacing))};
  };
  for (int i = 0; i < static_cast<int>(points.rows()); ++i) {
    const Eigen::Vector3d p = points.row(i).transpose();
    const std::array<long, 3> c = cell_of(p);
    bool near = false;
    for (long a = -1; a <= 1 && !near; ++a)
      for (long b = -1; b <= 1 && !near; ++b)
        for (long d = -1; d <= 1 && !near; ++d) {
          const auto it = cells.find({c[0] + a, c[1] + b, c[2] + d});
          if (it == cells.end()) continue;
          for (int j : it->second)
            if ((points.row(j).transpose() - p).squaredNorm() < spacing * spacing) near = true;
        }
    if (near) continue;
    keep.push_back(i);
    cells[c].push_back(i);
  }
  return keep;
}

ContactSamples Shell::contact_samples(int per_cell) const {
  // A regular grid of per_cell x per_cell samples a control cell at the sheet's mid-thickness
  // (r = 1/2, where the mesh lies), through the mesh's own in-plane map (mesh_interp_), so a
  // sample moves as the mesh there does; kept where the sheet's cell under it is inside (no
  // contact where there is no sheet). A sample is sum_k w_k x_k over its couples' two layers:
  // on a flat sheet the lattice rests as an affine grid and both maps reproduce it, so this is
  // the mesh's rest + displacement form to rounding.
  const int n = per_cell * (M_ - 1) + 1, N = sheet_->cells();
  std::map<std::vector<int>, std::vector<std::pair<int, std::vector<double>>>> by_stencil;
  int stencil = 0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) {
      const double st_s = double(a) / per_cell, st_t = double(b) / per_cell;
      const double u = st_t / (M_ - 1) * sheet_->size_u(), v = st_s / (M_ - 1) * sheet_->size_v();
      const int col = std::clamp(static_cast<int>(u / sheet_->du()), 0, N - 1);
      const int row = std::clamp(static_cast<int>(v / sheet_->dv()), 0, N - 1);
      if (!sheet_->inside()[row * N + col]) continue;
      int cp[9];
      double w[9];
      const int k = lattice_->plane_stencil(st_s, st_t, mesh_interp_, cp, w);
      stencil = 2 * k;
      std::vector<int> key(cp, cp + k);
      std::vector<double> weights;
      for (int q = 0; q < k; ++q) weights.insert(weights.end(), {0.5 * w[q], 0.5 * w[q]});
      by_stencil[key].emplace_back(a * n + b, std::move(weights));
    }
  ContactSamples out;
  out.stencil = stencil;
  out.spacing = std::max(sheet_->size_u(), sheet_->size_v()) / (M_ - 1) / per_cell;
  out.group.push_back(0);
  for (const auto& [couples, items] : by_stencil) {
    for (const auto& item : items) {
      for (int c : couples) out.vertex.insert(out.vertex.end(), {2 * c, 2 * c + 1});
      out.weight.insert(out.weight.end(), item.second.begin(), item.second.end());
    }
    out.group.push_back(out.size());
  }
  return out;
}

void Shell::cell_couples(int cell, int* couple, double* w) const {
  const int N = sheet_->cells();
  const Eigen::Vector2d st = sheet_->lattice_st((cell % N + 0.5) * sheet_->du(), (cell / N + 0.5) * sheet_->dv(), M_);
  bilinear_couples(st.x(), st.y(), couple, w);
}

Eigen::Vector3d Shell::cell_position(int cell) const {
  if (control_) return control_->point(surface_cells_, cell, lattice_->positions());
  // Rest position plus the lattice's displacement at the cell centre, mid-thickness: the same
  // FFD as the mesh's vertices, evaluated for one point on demand, so only the cells the front
  // and the emitters touch are ever deformed.
  Eigen::Vector3d p = sheet_->cell_rest().row(cell).transpose();
  const int N = sheet_->cells();
  const Eigen::Vector2d st = sheet_->lattice_st((cell % N + 0.5) * sheet_->du(), (cell / N + 0.5) * sheet_->dv(), M_);
  int cp[9];
  double w[9];
  const int n = lattice_->plane_stencil(st.x(), st.y(), mesh_interp_, cp, w);
  const RowMatX3& x = lattice_->positions();
  const RowMatX3& x0 = lattice_->rest();
  for (int k = 0; k < n; ++k)
    p += (0.5 * w[k]) * (x.row(2 * cp[k]) - x0.row(2 * cp[k]) + x.row(2 * cp[k] + 1) - x0.row(2 * cp[k] + 1)).transpose();
  return p;
}

Eigen::Vector3d Shell::cell_normal(int cell) const {
  if (!control_) throw std::logic_error("cell_normal: a grid lattice's cells take their normals from the grid");
  return control_->normal(surface_cells_, cell, lattice_->positions());
}

void Shell::quad_displacement_bounds(RowMatX3& lo, RowMatX3& hi) const {
  if (control_) throw std::logic_error("quad_displacement_bounds: a control surface has no grid quads");
  // A quad's cells move by convex combinations (the spline's weights are >= 0 and sum to 1) of
  // the mid-layer displacements of the couples within one of its corners (its 4 x 4 block).
  const RowMatX3& x = lattice_->positions();
  const RowMatX3& x0 = lattice_->rest();
  const int q = M_ - 1;
  lo.resize(q * q, 3);
  hi.resize(q * q, 3);
  for (int i = 0; i < q; ++i)
    for (int j = 0; j < q; ++j) {
      Eigen::RowVector3d l = Eigen::RowVector3d::Constant(std::numeric_limits<double>::infinity()), h = -l;
      for (int ii = std::max(0, i - 1); ii <= std::min(M_ - 1, i + 2); ++ii)
        for (int jj = std::max(0, j - 1); jj <= std::min(M_ - 1, j + 2); ++jj) {
          const int c = ii * M_ + jj;
          const Eigen::RowVector3d d = 0.5 * (x.row(2 * c) - x0.row(2 * c) + x.row(2 * c + 1) - x0.row(2 * c + 1));
          l = l.cwiseMin(d);
          h = h.cwiseMax(d);
        }
      lo.row(i * q + j) = l;
      hi.row(i * q + j) = h;
    }
}

template <class F>
void Shell::for_cell_shares(int cell, F&& f) const {
  if (control_) {
    constexpr int S = SurfaceEmbedding::kStencil;
    for (int q = 0; q < S; ++q) {
      const double w = surface_cells_.share[std::size_t(cell) * S + q];
      if (w > 0.0) f(surface_cells_.couple[std::size_t(cell) * S + q], w);
    }
    return;
  }
  int cp[4];
  double w[4];
  cell_couples(cell, cp, w);
  for (int k = 0; k < 4; ++k) f(cp[k], w[k]);
}

void Shell::add_cell_mass(int cell, double dm) {
  for_cell_shares(cell, [&](int c, double w) {
    control_mass_[2 * c] += 0.5 * w * dm;
    control_mass_[2 * c + 1] += 0.5 * w * dm;
  });
  mass_dirty_ = true;
}

void Shell::add_cell_area(int cell, Eigen::VectorXd& onto) const {
  const double a = cell_area_[cell];
  for_cell_shares(cell, [&](int c, double w) {
    for (int layer = 0; layer < 2; ++layer) onto[2 * c + layer] += 0.5 * w * a;
  });
}

void Shell::cell_burnt(int cell, double mass_lost) {
  add_cell_mass(cell, -mass_lost);
  add_cell_area(cell, burnt_area_);
  strength_dirty_ = true;
}

void Shell::set_dynamics_params(const DynamicsParams& p) {
  DynamicsParams dp = p;
  dp.has_floor = params_.has_floor;
  dp.floor_z = params_.floor_z - 0.5 * thickness_;
  dynamics_->set_params(dp);
  params_.dynamics = p;
}

void Shell::vertex_positions(RowMatX3& out) const {
  std::lock_guard<std::mutex> lock(mesh_mutex_);
  PhaseTimer timer(times_, Phase::Mesh);
  const double z_min = params_.has_floor ? params_.floor_z : -std::numeric_limits<double>::infinity();
  if (control_) return control_->deform(surface_vertices_, lattice_->positions(), out, z_min);
  out.resize(sheet_->vertices().rows(), 3);
  // The lattice's bottom layer is held half a thickness below the floor; the surface itself
  // never goes through it. Clamped inside deform's pass: a second pass over a strided column
  // cost as much as the deform itself on a million-vertex mesh.
  mesh_deform_->deform_into(*lattice_, vertex_embedding_, z_min, out);
  if (fold_blend_) fold_blend_->apply(*lattice_, z_min, out);
}

void Shell::vertex_positions_into(Eigen::Ref<RowMatX3> out) const {
  if (control_) {
    RowMatX3 tmp;
    vertex_positions(tmp);
    out = tmp;
    return;
  }
  std::lock_guard<std::mutex> lock(mesh_mutex_);
  PhaseTimer timer(times_, Phase::Mesh);
  const double z_min = params_.has_floor ? params_.floor_z : -std::numeric_limits<double>::infinity();
  mesh_deform_->deform_into(*lattice_, vertex_embedding_, z_min, out);
  if (fold_blend_) fold_blend_->apply(*lattice_, z_min, out);
}

void Shell::mesh_points(const Eigen::Ref<const RowMatXi>& idx, const Eigen::Ref<const RowMatXd>& w,
                        RowMatX3& out) const {
  const double z_min = params_.has_floor ? params_.floor_z : -std::numeric_limits<double>::infinity();
  if (control_) {
    const Eigen::Index n = idx.rows();
    RowMatX3 rest = RowMatX3::Zero(n, 3);
    std::vector<int> seeds(static_cast<std::size_t>(n), -1);
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Index heaviest = 0;
      for (Eigen::Index k = 0; k < idx.cols(); ++k) {
        rest.row(i) += w(i, k) * surface_vertices_.rest.row(idx(i, k));
        if (w(i, k) > w(i, heaviest)) heaviest = k;
      }
      if (idx.cols() > 0) seeds[std::size_t(i)] = vertex_seed_[std::size_t(idx(i, heaviest))];
    }
    std::lock_guard<std::mutex> lock(mesh_mutex_);
    control_->deform(control_->embed(rest, seeds), lattice_->positions(), out, z_min);
    return;
  }
  const RowMatX2& param = sheet_->vertex_param();
  const RowMatX3& verts = sheet_->vertices();
  const Eigen::Index n = idx.rows();
  RowMatX3 coords(n, 3), rest(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Vector2d uv = Eigen::Vector2d::Zero();
    Eigen::Vector3d x = Eigen::Vector3d::Zero();
    for (Eigen::Index k = 0; k < idx.cols(); ++k) {
      uv += w(i, k) * param.row(idx(i, k)).transpose();
      x += w(i, k) * verts.row(idx(i, k)).transpose();
    }
    const Eigen::Vector2d st = sheet_->lattice_st(uv.x(), uv.y(), M_);
    coords.row(i) << st.x(), st.y(), 0.5;
    rest.row(i) = x.transpose();
  }
  // The same map as vertex_positions, without its cache (whose tolerance would blur a
  // measure taken along an edge).
  std::lock_guard<std::mutex> lock(mesh_mutex_);
  out.resize(n, 3);
  lattice_->deform(lattice_->embed(coords, rest, mesh_interp_), out, z_min);
  if (fold_blend_) {
    FoldBlend blend(lattice_->embed(coords, rest, LatticeInterp::Trilinear));
    blend.set_keep_out(fold_blend_->keep_out(), fold_blend_->keep_out_margin());
    blend.apply(*lattice_, z_min, out);
  }
}

void Shell::hand_over_masses_and_strength() {
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
}

void Shell::step(double dt, const ShellSources& src, const Eigen::Vector3d& wind) {
  {
    PhaseTimer timer(times_, Phase::Particles);
    if (src.emit_pos->rows() > 0) particles_->emit(*src.emit_pos, *src.emit_normal, *src.emit_len, dt, src.emit_side);
    particles_->step(dt, wind);
    keep_flames_outside(dt);
    particle_pos_ = particles_->positions();
    particle_temp_ = particles_->temperatures();
  }
  {
    PhaseTimer timer(times_, Phase::Heat);
    bending_->add_particle_heat(lattice_->positions(), particle_pos_, particle_temp_, dt);
    bending_->set_pyrolysis(lattice_->positions(), *src.ignition_points);
    bending_->rotation(rotation_);
  }
  PhaseTimer timer(times_, Phase::Dynamics);
  hand_over_masses_and_strength();
  dynamics_->set_wind(wind);
  // Far from the fire D creeps by micro-radians as faint heat arrives; passing those on would
  // keep the whole lattice awake. A couple's applied rotation follows D in steps of at least
  // kRotationQuantum, so regions at rest sleep while the error stays below that quantum.
  // And only as |D| grows: a face that dried and pyrolysed does not swell back when the heat
  // passing over it fluctuates. Following D both ways, the particles' flicker in the heat
  // term (alpha (T_top - T_bottom)) bent and unbent the curl step after step, and with the
  // floor's friction the sheet crawled like an inchworm: the symplectic integrator, which
  // keeps every such kick, carried the demo's A4 sheet 0.25 m across its table in 20 s at
  // dt = 1/240 s (0.2 mm with alpha = 0).
  constexpr double kRotationQuantum = 1e-3;  // rad
  if (applied_rotation_.size() != rotation_.size()) applied_rotation_ = Eigen::VectorXd::Zero(rotation_.size());
  for (Eigen::Index c = 0; c < rotation_.size(); ++c)
    if (std::abs(rotation_[c]) >= std::abs(applied_rotation_[c]) + kRotationQuantum) applied_rotation_[c] = rotation_[c];
  stats_ = dynamics_->step(dt, applied_rotation_, bending_->heat_rate());
  update_piece_rotations();
}

void Shell::find_pieces() {
  // Connected pieces of the lattice (its couple neighbours), breadth-first: one on a grid.
  const LatticeTopology& t = dynamics_->topology();
  const int C = t.couples;
  piece_of_.assign(C, -1);
  int pieces = 0;
  std::vector<int> queue;
  for (int start = 0; start < C; ++start) {
    if (piece_of_[start] >= 0) continue;
    queue.assign(1, start);
    piece_of_[start] = pieces;
    for (std::size_t q = 0; q < queue.size(); ++q)
      for (int j = t.nbr_offset[queue[q]]; j < t.nbr_offset[queue[q] + 1]; ++j)
        if (piece_of_[t.nbr_index[j]] < 0) {
          piece_of_[t.nbr_index[j]] = pieces;
          queue.push_back(t.nbr_index[j]);
        }
    ++pieces;
  }
  piece_rotation_.assign(pieces, Eigen::Matrix3d::Identity());
  // A surface cell's piece: that of the couple carrying the largest share of it (a grid
  // lattice is one piece: cell_piece_ stays empty).
  if (!control_) return;
  outside_keeper_ = std::make_unique<OutsideKeeper>(piece_of_, control_->cells().on_boundary(), lattice_->rest(),
                                                    control_->spacing());
  if (!outside_keeper_->any()) outside_keeper_.reset();
  constexpr int S = SurfaceEmbedding::kStencil;
  cell_piece_.resize(surface_cells_.size());
  for (Eigen::Index cell = 0; cell < surface_cells_.size(); ++cell) {
    int best = 0;
    for (int q = 1; q < S; ++q)
      if (surface_cells_.share[std::size_t(cell) * S + q] > surface_cells_.share[std::size_t(cell) * S + best]) best = q;
    cell_piece_[cell] = piece_of_[surface_cells_.couple[std::size_t(cell) * S + best]];
  }
}

void Shell::update_piece_rotations() {
  // Each piece's best rigid rotation since rest (Kabsch on its couples' mid-points, weighted by
  // mass): what the piece did as a whole, which eq 1's slope must not count.
  const RowMatX3& x = lattice_->positions();
  const RowMatX3& x0 = lattice_->rest();
  const int P = static_cast<int>(piece_rotation_.size());
  std::vector<Eigen::Vector3d> c(P, Eigen::Vector3d::Zero()), c0(P, Eigen::Vector3d::Zero());
  std::vector<double> m(P, 0.0);
  auto mid = [](const RowMatX3& y, int k) { return Eigen::Vector3d(0.5 * (y.row(2 * k) + y.row(2 * k + 1)).transpose()); };
  const int C = static_cast<int>(piece_of_.size());
  Eigen::VectorXd w(C);  // a couple's mass (a massless one still counts a little)
  for (int k = 0; k < C; ++k) w[k] = control_mass_[2 * k] + control_mass_[2 * k + 1] + 1e-12;
  for (int k = 0; k < C; ++k) {
    c[piece_of_[k]] += w[k] * mid(x, k);
    c0[piece_of_[k]] += w[k] * mid(x0, k);
    m[piece_of_[k]] += w[k];
  }
  std::vector<Eigen::Matrix3d> H(P, Eigen::Matrix3d::Zero());
  for (int p = 0; p < P; ++p) c[p] /= m[p], c0[p] /= m[p];
  for (int k = 0; k < C; ++k) {
    const int p = piece_of_[k];
    H[p] += w[k] * (mid(x0, k) - c0[p]) * (mid(x, k) - c[p]).transpose();
    // The couples' axes too, so that a piece of coplanar couples has a defined turn about them.
    H[p] += w[k] * (x0.row(2 * k + 1) - x0.row(2 * k)).transpose() * (x.row(2 * k + 1) - x.row(2 * k));
  }
  for (int p = 0; p < P; ++p) {
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(H[p], Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
    if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0) D(2, 2) = -1.0;
    piece_rotation_[p] = svd.matrixV() * D * svd.matrixU().transpose();
  }
}

void Shell::keep_flames_outside(double dt) {
  // Half a lattice thickness out: the flames' side of the layer, as where they are born.
  // Nothing to keep out while no particle lives (the burnt shares are only for them).
  if (!outside_keeper_ || particles_->count() == 0) return;
  const int C = static_cast<int>(piece_of_.size());
  couple_burnt_.resize(C);
  for (int c = 0; c < C; ++c)
    couple_burnt_[c] = control_area_[2 * c] > 0 ? burnt_area_[2 * c] / control_area_[2 * c] : 0.0;
  outside_keeper_->apply(lattice_->positions(), couple_burnt_, 0.5 * thickness_, dt, *particles_);
}

Eigen::Vector3d Shell::turned_rest_normal(int cell, const Eigen::Vector3d& rest_normal) const {
  return piece_rotation_[cell_piece_.empty() ? 0 : cell_piece_[cell]] * rest_normal;
}

Shell::Checkpoint Shell::checkpoint() const {
  return Checkpoint{control_mass_, burnt_area_, strength_, applied_rotation_, piece_rotation_, mass_dirty_, strength_dirty_,
                    stats_, std::make_unique<ParticleSystem>(*particles_), std::make_unique<Bending>(*bending_),
                    lattice_->positions(), dynamics_->checkpoint()};
}

void Shell::rollback(Checkpoint&& c) {
  control_mass_ = std::move(c.control_mass);
  burnt_area_ = std::move(c.burnt_area);
  strength_ = std::move(c.strength);
  applied_rotation_ = std::move(c.applied_rotation);
  piece_rotation_ = std::move(c.piece_rotation);
  mass_dirty_ = c.mass_dirty;
  strength_dirty_ = c.strength_dirty;
  stats_ = c.stats;
  particles_ = std::move(c.particles);
  bending_ = std::move(c.bending);
  lattice_->positions() = c.lattice;
  dynamics_->rollback(std::move(c.dynamics));
}

}  // namespace thinburn
