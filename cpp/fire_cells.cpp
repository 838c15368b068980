#include "fire_cells.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <limits>

namespace thinburn {
namespace {

std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Real sheets vary over centimetres, not per cell: a smooth value-noise field between random
// values every kNoiseScale cells, plus a little per-cell grain.
constexpr int kNoiseScale = 10;
constexpr double kSmoothShare = 0.75;

// Barycentric weights of the point of triangle abc closest to p (Ericson, Real-Time Collision
// Detection, 5.1.5): a point off the triangle takes its nearest edge's or corner's value.
Eigen::Vector3d closest_barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

}  // namespace

std::vector<double> vertex_field_at_cells(const FireCells& cells, const RowMatX3& V, const RowMatX3i& F,
                                          const Eigen::VectorXd& values, bool sharp_zero) {
  const int nv = static_cast<int>(V.rows());
  std::vector<Eigen::Vector3d> pts(nv);
  for (int i = 0; i < nv; ++i) pts[i] = V.row(i).transpose();
  const KdTree3 tree(pts);
  std::vector<std::vector<int>> faces_of(nv);
  for (int f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) faces_of[F(f, k)].push_back(f);
  std::vector<double> out(cells.size());
  std::vector<int> candidates;
  for (int c = 0; c < cells.size(); ++c) {
    const Eigen::Vector3d q = cells.rest(c);
    const int v = tree.nearest(q);
    // The faces around the nearest vertex and around its neighbours: the triangle holding q
    // is among them unless the mesh has slivers longer than two rings.
    candidates.clear();
    for (int f : faces_of[v])
      for (int k = 0; k < 3; ++k) candidates.insert(candidates.end(), faces_of[F(f, k)].begin(), faces_of[F(f, k)].end());
    double best_d2 = std::numeric_limits<double>::infinity();
    double value = values[v];  // a vertex on no face: its own value
    int major = v;             // the triangle's vertex with the largest weight
    for (int f : candidates) {
      const Eigen::Vector3d a = pts[F(f, 0)], b = pts[F(f, 1)], cc = pts[F(f, 2)];
      const Eigen::Vector3d w = closest_barycentric(q, a, b, cc);
      const double d2 = (w[0] * a + w[1] * b + w[2] * cc - q).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        value = w[0] * values[F(f, 0)] + w[1] * values[F(f, 1)] + w[2] * values[F(f, 2)];
        int k;
        w.maxCoeff(&k);
        major = F(f, k);
      }
    }
    // Zero is a firebreak, not a slow zone: interpolated, a line of zero vertices would only
    // slow the fire between them. A cell is zero where its nearest vertex is (a band one mesh
    // edge wide on a coarse mesh), or near a zero vertex (below).
    out[c] = sharp_zero && values[major] <= 0.0 ? 0.0 : value;
  }
  if (!sharp_zero) return out;
  // And every cell within a cell's spacing of a zero vertex: a painted line on a mesh about as
  // fine as the cells, or lying on the cells' borders, has no gap the front could slip through
  // (the nearest-vertex rule alone left 2 of 40 cells open on such a line).
  const double h = cells.spacing();
  auto key = [h](const Eigen::Vector3d& p) {
    const Eigen::Vector3d q = (p / h).array().floor();
    return std::array<std::int64_t, 3>{static_cast<std::int64_t>(q.x()), static_cast<std::int64_t>(q.y()),
                                       static_cast<std::int64_t>(q.z())};
  };
  std::map<std::array<std::int64_t, 3>, std::vector<int>> zeros;
  for (int i = 0; i < nv; ++i)
    if (values[i] <= 0.0) zeros[key(pts[i])].push_back(i);
  if (zeros.empty()) return out;
  for (int c = 0; c < cells.size(); ++c) {
    const Eigen::Vector3d q = cells.rest(c);
    const auto k = key(q);
    for (int d = 0; d < 27 && out[c] != 0.0; ++d) {
      const auto it = zeros.find({k[0] + d % 3 - 1, k[1] + (d / 3) % 3 - 1, k[2] + d / 9 - 1});
      if (it == zeros.end()) continue;
      for (int i : it->second)
        if ((pts[i] - q).squaredNorm() <= h * h) {
          out[c] = 0.0;
          break;
        }
    }
  }
  return out;
}

double seeded_uniform(std::uint64_t seed, std::uint64_t stream, std::uint64_t key) {
  const std::uint64_t h = mix(seed ^ mix(stream * 0x100000001b3ULL + key));
  return 2.0 * (static_cast<double>(h >> 11) * 0x1.0p-53) - 1.0;
}

// ---------------------------------------------------------------------------------------------
// GridCells

GridCells::GridCells(std::shared_ptr<const Sheet> sheet, FrontMethod method)
    : sheet_(std::move(sheet)), front_(sheet_->cells(), sheet_->cells(), sheet_->dv(), sheet_->du(), method) {
  front_.set_inside(sheet_->inside());
}

double GridCells::spacing() const { return std::sqrt(sheet_->du() * sheet_->dv()); }

double GridCells::reach() const { return 3.0 * std::max(sheet_->du(), sheet_->dv()); }

double GridCells::noise(int cell, std::uint64_t seed, std::uint64_t stream) const {
  const int N = sheet_->cells(), r = cell / N, c = cell % N;
  const int gr = r / kNoiseScale, gc = c / kNoiseScale;
  const double fr = (r % kNoiseScale + 0.5) / kNoiseScale, fc = (c % kNoiseScale + 0.5) / kNoiseScale;
  auto node = [&](int i, int j) {
    return seeded_uniform(seed, stream + 7, (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j));
  };
  const double smooth = (1 - fr) * ((1 - fc) * node(gr, gc) + fc * node(gr, gc + 1)) +
                        fr * ((1 - fc) * node(gr + 1, gc) + fc * node(gr + 1, gc + 1));
  return kSmoothShare * smooth + (1.0 - kSmoothShare) * seeded_uniform(seed, stream, static_cast<std::uint64_t>(cell));
}

Eigen::Vector3d GridCells::normal_from_neighbours(int cell, const CellView& view) const {
  const int N = sheet_->cells(), r = cell / N, c = cell % N;
  const int cl = std::max(c - 1, 0), cr = std::min(c + 1, N - 1), rd = std::max(r - 1, 0), ru = std::min(r + 1, N - 1);
  const Eigen::Vector3d n = (view.position(r * N + cr) - view.position(r * N + cl))
                                .cross(view.position(ru * N + c) - view.position(rd * N + c));
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : rest_normal(cell);
}

double GridCells::grad2(int cell, const CellView& view) const {
  // Rise over run of the current surface out of the (turned) rest plane, along rows and columns,
  // from central differences (one-sided at the outline), squared and summed: |grad h|².
  const int N = sheet_->cells(), r = cell / N, c = cell % N;
  const auto& in = sheet_->inside();
  // The rest plane's normal, turned with the sheet as a whole (a curtain the wind lifts is not
  // steeper for it; its folds are).
  const Eigen::Vector3d n = view.reference_normal(cell);
  auto slope2 = [&](int a, int b) {
    if (a == b) return 0.0;
    const Eigen::Vector3d d = view.position(b) - view.position(a);
    const double rise = d.dot(n), run = (d - rise * n).norm();
    return run > 0 ? (rise * rise) / (run * run) : 0.0;
  };
  auto pick = [&](int rr, int cc) { return (rr >= 0 && rr < N && cc >= 0 && cc < N && in[rr * N + cc]) ? rr * N + cc : cell; };
  return slope2(pick(r, c - 1), pick(r, c + 1)) + slope2(pick(r - 1, c), pick(r + 1, c));
}

LocalSpeed GridCells::local_speed(int cell, const SpreadLaw& law, const CellView& view) const {
  LocalSpeed s{law.v(cell), 0.0, 0.0};
  if (law.drive.isZero()) return s;
  // The drive vector in grid axes: projected on the local row and column tangents.
  const int N = sheet_->cells(), r = cell / N, c = cell % N;
  const int cl = std::max(c - 1, 0), cr = std::min(c + 1, N - 1), rd = std::max(r - 1, 0), ru = std::min(r + 1, N - 1);
  Eigen::Vector3d t_col = view.position(r * N + cr) - view.position(r * N + cl);
  Eigen::Vector3d t_row = view.position(ru * N + c) - view.position(rd * N + c);
  if (t_col.norm() > 0) t_col.normalize();
  if (t_row.norm() > 0) t_row.normalize();
  s.e_row = law.drive.dot(t_row);
  s.e_col = law.drive.dot(t_col);
  const double e = std::hypot(s.e_row, s.e_col);
  if (e > law.max_drive) {
    s.e_row *= law.max_drive / e;
    s.e_col *= law.max_drive / e;
  }
  return s;
}

SpeedFn GridCells::speed_fn(const SpreadLaw& law, const CellView& view) const {
  return [this, &law, &view](int cell) { return local_speed(cell, law, view); };
}

bool GridCells::on_fringe(int cell, const std::vector<std::uint8_t>& state) const {
  const int N = sheet_->cells(), r = cell / N, col = cell % N;
  const auto& in = sheet_->inside();
  for (int dr = -1; dr <= 1; ++dr)
    for (int dc = -1; dc <= 1; ++dc) {
      const int rr = r + dr, cc = col + dc;
      if ((dr || dc) && rr >= 0 && rr < N && cc >= 0 && cc < N && in[rr * N + cc] && state[rr * N + cc] == 0)
        return true;
    }
  return false;
}

void GridCells::ignite(int cell, double t0, const SpreadLaw& law, const CellView& view) {
  const int N = sheet_->cells();
  front_.ignite(FrontSource{static_cast<double>(cell / N), static_cast<double>(cell % N), t0}, speed_fn(law, view));
}

const std::vector<int>& GridCells::advance(double t_end, const SpreadLaw& law, const CellView& view) {
  return front_.advance(t_end, speed_fn(law, view));
}

// ---------------------------------------------------------------------------------------------
// ShellCells

ShellCells::ShellCells(const RowMatX3& vertices, const RowMatX3i& faces, int cells)
    : cells_([&] {
        CellOptions opt;
        opt.cells = cells;
        return std::make_shared<const SurfaceCells>(vertices, faces, opt);
      }()),
      front_(cells_) {
  inside_.assign(cells_->size(), 1);
  const auto& vc = cells_->vertex_cells();
  const auto& vw = cells_->vertex_weights();
  vertex_cell_.resize(vc.size());
  for (std::size_t i = 0; i < vc.size(); ++i) {
    int best = 0;
    for (int k = 1; k < 3; ++k)
      if (vw[i][k] > vw[i][best]) best = k;
    vertex_cell_[i] = vc[i][best];
  }
  noise_scale_ = kNoiseScale * cells_->spacing();
}

double ShellCells::noise(int cell, std::uint64_t seed, std::uint64_t stream) const {
  // The grid's value noise in 3-D: trilinear between random values on a cubic lattice of
  // kNoiseScale cells' spacing, so the field does not depend on how cells are numbered.
  const Eigen::Vector3d q = cells_->positions()[cell] / noise_scale_;
  const Eigen::Vector3d f = q.array().floor();
  const Eigen::Vector3d a = q - f;
  const std::int64_t base[3] = {static_cast<std::int64_t>(f.x()), static_cast<std::int64_t>(f.y()),
                                static_cast<std::int64_t>(f.z())};
  double smooth = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    double w = 1.0;
    std::uint64_t key = 0;
    for (int d = 0; d < 3; ++d) {
      const int bit = (corner >> d) & 1;
      w *= bit ? a[d] : 1.0 - a[d];
      key = mix(key ^ static_cast<std::uint64_t>(base[d] + bit));
    }
    smooth += w * seeded_uniform(seed, stream + 7, key);
  }
  return kSmoothShare * smooth + (1.0 - kSmoothShare) * seeded_uniform(seed, stream, static_cast<std::uint64_t>(cell));
}

double ShellCells::grad2(int cell, const CellView& view) const {
  // The grid's |grad h|^2 is tan^2 of the angle the surface turned out of its rest plane; on a
  // shell, the angle its normal turned from the rest normal, less the turn of its whole piece.
  const double c = std::clamp(view.normal(cell).dot(view.reference_normal(cell)), -1.0, 1.0);
  if (c <= 1e-6) return 1e12;  // turned by 90 degrees or more: as steep as it gets
  return (1.0 - c * c) / (c * c);
}

SurfaceSpeed ShellCells::local_speed(int cell, const SpreadLaw& law, const CellView& view) const {
  SurfaceSpeed s{law.v(cell)};
  if (law.drive.isZero()) return s;
  const Eigen::Vector3d n = view.normal(cell), n0 = rest_normal(cell);
  Eigen::Vector3d e = law.drive - law.drive.dot(n) * n;  // along the sheet now
  // Carried to the rest tangent plane by the smallest rotation taking n to n0.
  e = Eigen::Quaterniond::FromTwoVectors(n, n0) * e;
  e -= e.dot(n0) * n0;
  const double len = e.norm();
  if (len > law.max_drive) e *= law.max_drive / len;
  s.e = e;
  return s;
}

SurfaceSpeedFn ShellCells::speed_fn(const SpreadLaw& law, const CellView& view) const {
  return [this, &law, &view](int cell) { return local_speed(cell, law, view); };
}

bool ShellCells::on_fringe(int cell, const std::vector<std::uint8_t>& state) const {
  for (int q = cells_->nbr_offset()[cell]; q < cells_->nbr_offset()[cell + 1]; ++q)
    if (state[cells_->nbr_index()[q]] == 0) return true;
  return false;
}

void ShellCells::ignite(int cell, double t0, const SpreadLaw& law, const CellView& view) {
  front_.ignite_cell(cell, t0, speed_fn(law, view));
}

void ShellCells::ignite_point(int cell, const Eigen::Vector3d& offset, double t0, const SpreadLaw& law,
                              const CellView& view) {
  front_.ignite_point(rest(cell) + offset, t0, speed_fn(law, view));
}

const std::vector<int>& ShellCells::advance(double t_end, const SpreadLaw& law, const CellView& view) {
  return front_.advance(t_end, speed_fn(law, view));
}

void ShellCells::cells_to_vertices(const double* v, double* out) const {
  const auto& vc = cells_->vertex_cells();
  const auto& vw = cells_->vertex_weights();
  for (std::size_t i = 0; i < vc.size(); ++i) {
    // Clamped to the values combined, as on the grid: a field in [0, 1] stays there.
    double s = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < 3; ++k) {
      if (vw[i][k] == 0.0) continue;
      s += vw[i][k] * v[vc[i][k]];
      lo = std::min(lo, v[vc[i][k]]);
      hi = std::max(hi, v[vc[i][k]]);
    }
    out[i] = lo <= hi ? std::clamp(s, lo, hi) : s;
  }
}

}  // namespace thinburn
