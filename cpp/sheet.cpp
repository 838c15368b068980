#include "sheet.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>

namespace thinburn {
namespace {

double triangle_area(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  return 0.5 * (b - a).cross(c - a).norm();
}

double signed_area_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x()));
}

// The best-fit plane's frame, oriented the way a Blender user expects: a lying sheet faces
// up (+z), and a hanging one has its v axis pointing up, so "rows" grow upward.
SheetFrame best_fit_frame(const RowMatX3& V) {
  SheetFrame f;
  f.origin = V.colwise().mean().transpose();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (Eigen::Index i = 0; i < V.rows(); ++i) {
    Eigen::Vector3d d = V.row(i).transpose() - f.origin;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  f.n = es.eigenvectors().col(0).normalized();  // smallest spread
  const double tilt_eps = 1e-6;
  if (f.n.z() < -tilt_eps) f.n = -f.n;
  Eigen::Vector3d u = Eigen::Vector3d::UnitX() - f.n * f.n.x();
  if (u.norm() < 1e-6) u = Eigen::Vector3d::UnitY() - f.n * f.n.y();
  f.u = u.normalized();
  f.v = f.n.cross(f.u);
  if (std::abs(f.n.z()) <= tilt_eps && f.v.z() < 0) {  // hanging sheet: keep v up
    f.n = -f.n;
    f.v = -f.v;
  }
  return f;
}

}  // namespace

Sheet::Sheet(const RowMatX3& vertices, const RowMatX3i& faces, const RowMatX2& uv, int cells)
    : n_(cells), vertices_(vertices) {
  if (cells < 2) throw std::invalid_argument("cells must be >= 2");
  if (vertices.rows() < 3 || faces.rows() < 1) throw std::invalid_argument("vertices/faces: empty mesh");
  if (faces.minCoeff() < 0 || faces.maxCoeff() >= vertices.rows())
    throw std::invalid_argument("faces: indices out of range");
  if (uv.rows() != 0 && uv.rows() != vertices.rows()) throw std::invalid_argument("uv: one row per vertex expected");
  if (!vertices.allFinite() || !uv.allFinite()) throw std::invalid_argument("vertices/uv: NaN or inf");
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    area_ += triangle_area(vertices.row(faces(f, 0)), vertices.row(faces(f, 1)), vertices.row(faces(f, 2)));
  if (!(area_ > 0)) throw std::invalid_argument("faces: the mesh has zero area");
  frame_ = best_fit_frame(vertices);
  build_parameterisation(uv, faces);
  rasterise(faces);
  fill_outside();
  build_normals();
  build_vertex_weights();
}

// UV is unitless and may be stretched or sheared. Map it by the square root of its average
// metric tensor (the mean of J^T J over triangles, J the UV-to-3-D Jacobian), so parameter
// lengths are metres on average in every direction and cells keep their aspect in 3-D.
static Eigen::Matrix2d uv_metric_root(const RowMatX3& V, const RowMatX3i& F, const RowMatX2& uv) {
  Eigen::Matrix2d G = Eigen::Matrix2d::Zero();
  double total = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    Eigen::Matrix2d e;
    e.col(0) = (uv.row(F(f, 1)) - uv.row(F(f, 0))).transpose();
    e.col(1) = (uv.row(F(f, 2)) - uv.row(F(f, 0))).transpose();
    const double a = std::abs(e.determinant()) * 0.5;
    if (a < 1e-300) continue;
    Eigen::Matrix<double, 3, 2> E;
    E.col(0) = (V.row(F(f, 1)) - V.row(F(f, 0))).transpose();
    E.col(1) = (V.row(F(f, 2)) - V.row(F(f, 0))).transpose();
    const Eigen::Matrix<double, 3, 2> J = E * e.inverse();
    G += a * (J.transpose() * J);
    total += a;
  }
  if (!(total > 0)) throw std::invalid_argument("uv: the UV layout has zero area");
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(G / total);
  if (!(es.eigenvalues().minCoeff() > 0)) throw std::invalid_argument("uv: the UV layout is degenerate");
  return es.operatorSqrt();
}

void Sheet::build_parameterisation(const RowMatX2& uv, const RowMatX3i& faces) {
  const Eigen::Index nv = vertices_.rows();
  RowMatX2 p(nv, 2);
  if (uv.rows() == 0) {
    for (Eigen::Index i = 0; i < nv; ++i) {
      Eigen::Vector3d d = vertices_.row(i).transpose() - frame_.origin;
      p(i, 0) = d.dot(frame_.u);
      p(i, 1) = d.dot(frame_.v);
    }
  } else {
    p = uv * uv_metric_root(vertices_, faces, uv).transpose();
  }
  Eigen::Vector2d lo = p.colwise().minCoeff(), hi = p.colwise().maxCoeff();
  if (!(hi.x() > lo.x()) || !(hi.y() > lo.y()))
    throw std::invalid_argument(uv.rows() ? "uv: the UV layout has zero extent" : "vertices: the mesh is degenerate (a line or a point)");
  vertex_param_ = p.rowwise() - lo.transpose();
  du_ = (hi.x() - lo.x()) / n_;
  dv_ = (hi.y() - lo.y()) / n_;
}

void Sheet::rasterise(const RowMatX3i& faces) {
  const int N = n_;
  inside_.assign(static_cast<size_t>(N) * N, 0);
  cell_rest_ = RowMatX3::Zero(N * N, 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector2d a = vertex_param_.row(faces(f, 0)), b = vertex_param_.row(faces(f, 1)),
                          c = vertex_param_.row(faces(f, 2));
    const double area2 = signed_area_2d(a, b, c);
    if (std::abs(area2) < 1e-300) continue;
    const int c0 = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}) / du_ - 0.5)));
    const int c1 = std::min(N - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}) / du_ - 0.5)));
    const int r0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}) / dv_ - 0.5)));
    const int r1 = std::min(N - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}) / dv_ - 0.5)));
    const double eps = -1e-9;
    for (int r = r0; r <= r1; ++r)
      for (int col = c0; col <= c1; ++col) {
        const int cell = r * N + col;
        if (inside_[cell]) continue;
        const Eigen::Vector2d q((col + 0.5) * du_, (r + 0.5) * dv_);
        const double wa = signed_area_2d(q, b, c) / area2, wb = signed_area_2d(a, q, c) / area2;
        const double wc = 1.0 - wa - wb;
        if (wa < eps || wb < eps || wc < eps) continue;
        inside_[cell] = 1;
        cell_rest_.row(cell) = wa * vertices_.row(faces(f, 0)) + wb * vertices_.row(faces(f, 1)) +
                               wc * vertices_.row(faces(f, 2));
      }
  }
  // A vertex's own cell belongs to the sheet even when the cell centre misses every
  // triangle, so thin strips and ragged outlines are not lost.
  for (Eigen::Index i = 0; i < vertices_.rows(); ++i) {
    const int col = std::clamp(static_cast<int>(vertex_param_(i, 0) / du_), 0, N - 1);
    const int r = std::clamp(static_cast<int>(vertex_param_(i, 1) / dv_), 0, N - 1);
    if (!inside_[r * N + col]) {
      inside_[r * N + col] = 1;
      cell_rest_.row(r * N + col) = vertices_.row(i);
    }
  }
}

void Sheet::fill_outside() {
  // Breadth-first from the inside cells: an outside cell takes the rest position of its
  // nearest inside cell, shifted by the in-plane offset, so a lattice draped over the grid
  // continues the sheet's surface smoothly past its outline.
  const int N = n_;
  std::vector<int> source(N * N, -1);
  std::deque<int> queue;
  for (int c = 0; c < N * N; ++c)
    if (inside_[c]) {
      source[c] = c;
      queue.push_back(c);
    }
  while (!queue.empty()) {
    const int c = queue.front();
    queue.pop_front();
    const int r = c / N, col = c % N;
    const int nb[4][2] = {{r - 1, col}, {r + 1, col}, {r, col - 1}, {r, col + 1}};
    for (const auto& q : nb) {
      if (q[0] < 0 || q[0] >= N || q[1] < 0 || q[1] >= N) continue;
      const int d = q[0] * N + q[1];
      if (source[d] >= 0) continue;
      source[d] = source[c];
      queue.push_back(d);
    }
  }
  nearest_inside_ = source;
  for (int c = 0; c < N * N; ++c) {
    if (inside_[c]) continue;
    const int s = source[c];
    const double dcol = (c % N - s % N) * du_, drow = (c / N - s / N) * dv_;
    cell_rest_.row(c) = cell_rest_.row(s) + dcol * frame_.u.transpose() + drow * frame_.v.transpose();
  }
}

void Sheet::build_normals() {
  const int N = n_;
  cell_normal_.resize(N * N, 3);
  for (int r = 0; r < N; ++r)
    for (int c = 0; c < N; ++c) {
      const int cl = std::max(c - 1, 0), cr = std::min(c + 1, N - 1);
      const int rd = std::max(r - 1, 0), ru = std::min(r + 1, N - 1);
      const Eigen::Vector3d tu = cell_rest_.row(r * N + cr) - cell_rest_.row(r * N + cl);
      const Eigen::Vector3d tv = cell_rest_.row(ru * N + c) - cell_rest_.row(rd * N + c);
      Eigen::Vector3d n = tu.cross(tv);
      const double len = n.norm();
      cell_normal_.row(r * N + c) = len > 0 ? Eigen::Vector3d(n / len) : frame_.n;
    }
}

void Sheet::build_vertex_weights() {
  const int N = n_;
  const Eigen::Index nv = vertices_.rows();
  vertex_cell_.resize(nv);
  vw_cell_.resize(4 * nv);
  vw_weight_.resize(4 * nv);
  for (Eigen::Index i = 0; i < nv; ++i) {
    const int col = std::clamp(static_cast<int>(vertex_param_(i, 0) / du_), 0, N - 1);
    const int r = std::clamp(static_cast<int>(vertex_param_(i, 1) / dv_), 0, N - 1);
    vertex_cell_[i] = nearest_inside_[r * N + col];
    // Bilinear weights between the four surrounding cell centres.
    const double fc = std::clamp(vertex_param_(i, 0) / du_ - 0.5, 0.0, N - 1.0);
    const double fr = std::clamp(vertex_param_(i, 1) / dv_ - 0.5, 0.0, N - 1.0);
    const int c0 = std::min(static_cast<int>(fc), N - 2), r0 = std::min(static_cast<int>(fr), N - 2);
    const double a = fc - c0, b = fr - r0;
    const int cells[4] = {r0 * N + c0, r0 * N + c0 + 1, (r0 + 1) * N + c0, (r0 + 1) * N + c0 + 1};
    double w[4] = {(1 - a) * (1 - b), a * (1 - b), (1 - a) * b, a * b};
    double total = 0;
    for (int k = 0; k < 4; ++k) {
      if (!inside_[cells[k]]) w[k] = 0;
      total += w[k];
    }
    for (int k = 0; k < 4; ++k) {
      vw_cell_[4 * i + k] = total > 1e-12 ? cells[k] : vertex_cell_[i];
      vw_weight_[4 * i + k] = total > 1e-12 ? w[k] / total : (k == 0 ? 1.0 : 0.0);
    }
  }
}

void Sheet::cells_to_vertices(const double* cell_values, double* out) const {
  const Eigen::Index nv = vertices_.rows();
  for (Eigen::Index i = 0; i < nv; ++i) {
    // A convex combination (weights >= 0 summing to 1 up to rounding): the result is clamped to
    // the range of the values it combines, so that ones map to exactly 1 and a field in [0, 1]
    // (char) stays in [0, 1]; rounding of the weights' sum alone gave 1 + 1 ulp.
    double s = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int k = 0; k < 4; ++k) {
      const double w = vw_weight_[4 * i + k];
      if (w == 0.0) continue;
      const double c = cell_values[vw_cell_[4 * i + k]];
      s += w * c;
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
    out[i] = lo <= hi ? std::clamp(s, lo, hi) : s;
  }
}

Eigen::Vector2d Sheet::lattice_st(double u, double v, int M) const {
  return {v / size_v() * (M - 1), u / size_u() * (M - 1)};
}

}  // namespace thinburn
