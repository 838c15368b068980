#include "colliders.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace thinburn {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

void check_coefficients(const char* what, double friction, double thickness) {
  require(std::isfinite(friction) && friction >= 0.0,
          std::string(what) + ": friction must be finite and >= 0, got " + std::to_string(friction));
  require(std::isfinite(thickness) && thickness >= 0.0,
          std::string(what) + ": thickness must be finite and >= 0, got " + std::to_string(thickness));
}

void check_rotation(const char* what, const Eigen::Matrix3d& R) {
  require(R.allFinite(), std::string(what) + ": rotation must be finite");
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  require(err < 1e-6 && R.determinant() > 0.0,
          std::string(what) + ": rotation must be a rotation matrix (orthonormal, determinant +1)");
}

// Sign of the 2-d orientation of (0, p1, p2), ties broken by a fixed rule so that a point on a
// shared edge is inside exactly one of the two triangles (Bridson's SDFGen): each crossing of a
// grid line through a closed surface is counted once.
int orientation(double x1, double y1, double x2, double y2, double& twice_area) {
  twice_area = y1 * x2 - x1 * y2;
  if (twice_area > 0) return 1;
  if (twice_area < 0) return -1;
  if (y2 > y1) return 1;
  if (y2 < y1) return -1;
  if (x1 > x2) return 1;
  if (x1 < x2) return -1;
  return 0;
}

// Is (y, z) in the 2-d triangle? If so, its barycentric weights.
bool in_triangle_2d(double y0, double z0, double y1, double z1, double y2, double z2, double y3,
                    double z3, double& a, double& b, double& c) {
  y1 -= y0, y2 -= y0, y3 -= y0;
  z1 -= z0, z2 -= z0, z3 -= z0;
  const int sa = orientation(y2, z2, y3, z3, a);
  if (sa == 0) return false;
  const int sb = orientation(y3, z3, y1, z1, b);
  if (sb != sa) return false;
  const int sc = orientation(y1, z1, y2, z2, c);
  if (sc != sa) return false;
  const double sum = a + b + c;
  if (sum == 0.0) return false;
  a /= sum, b /= sum, c /= sum;
  return true;
}

// Every edge must belong to exactly two faces: then the surface is closed and a ray's parity of
// crossings says inside or outside.
void check_closed(const Colliders::RowMatX3i& F) {
  std::map<std::pair<int, int>, int> uses;
  for (int f = 0; f < F.rows(); ++f)
    for (int e = 0; e < 3; ++e) {
      const int a = F(f, e), b = F(f, (e + 1) % 3);
      ++uses[{std::min(a, b), std::max(a, b)}];
    }
  for (const auto& [edge, count] : uses)
    require(count == 2, "meshes: the mesh is not closed: edge (" + std::to_string(edge.first) + ", " +
                            std::to_string(edge.second) + ") belongs to " + std::to_string(count) +
                            " face(s), not 2; a collider mesh must be watertight (no holes)");
}

}  // namespace

Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                    const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

int Colliders::add(Shape s) {
  shapes_.push_back(std::move(s));
  ++version_;
  return size() - 1;
}

void Colliders::check_index(int i, const char* what) const {
  if (i < 0 || i >= size())
    throw std::out_of_range(std::string(what) + ": collider index " + std::to_string(i) +
                            " out of range (" + std::to_string(size()) + " colliders)");
}

int Colliders::add_sphere(const Eigen::Vector3d& centre, double radius, double friction, double thickness) {
  require(centre.allFinite(), "spheres: centre must be finite");
  require(std::isfinite(radius) && radius > 0.0,
          "spheres: radius must be finite and > 0, got " + std::to_string(radius));
  check_coefficients("spheres", friction, thickness);
  Shape s{Kind::Sphere};
  s.t = centre;
  s.radius = radius;
  s.friction = friction;
  s.thickness = thickness;
  return add(std::move(s));
}

int Colliders::add_box(const Eigen::Vector3d& centre, const Eigen::Vector3d& half_extents,
                       const Eigen::Matrix3d& rotation, double friction, double thickness) {
  require(centre.allFinite(), "boxes: centre must be finite");
  require(half_extents.allFinite() && half_extents.minCoeff() > 0.0,
          "boxes: half_extents must be finite and > 0");
  check_rotation("boxes", rotation);
  check_coefficients("boxes", friction, thickness);
  Shape s{Kind::Box};
  s.t = centre;
  s.R = rotation;
  s.half = half_extents;
  s.friction = friction;
  s.thickness = thickness;
  return add(std::move(s));
}

int Colliders::add_mesh(const RowMatX3& V, const RowMatX3i& F, double friction, double thickness,
                        int resolution) {
  require(V.rows() >= 4 && F.rows() >= 4, "meshes: a closed mesh needs at least 4 vertices and 4 faces");
  require(V.allFinite(), "meshes: vertices must be finite (no NaN or inf)");
  require(F.minCoeff() >= 0 && F.maxCoeff() < V.rows(),
          "meshes: faces index vertices 0.." + std::to_string(V.rows() - 1));
  require(resolution >= 8 && resolution <= 512,
          "meshes: resolution must be in [8, 512] grid cells, got " + std::to_string(resolution));
  check_coefficients("meshes", friction, thickness);
  check_closed(F);

  // The grid: the mesh's box, padded by kPad cells so that a point near the surface, inside or
  // out, reads exact neighbours.
  constexpr int kPad = 4, kBand = 2;
  Grid g;
  const Eigen::Vector3d lo = V.colwise().minCoeff().transpose(), hi = V.colwise().maxCoeff().transpose();
  g.dx = (hi - lo).maxCoeff() / resolution;
  require(g.dx > 0.0, "meshes: the mesh is degenerate (all vertices at one point)");
  g.origin = lo - Eigen::Vector3d::Constant(kPad * g.dx);
  for (int a = 0; a < 3; ++a) g.n[a] = static_cast<int>(std::ceil((hi(a) - lo(a)) / g.dx)) + 1 + 2 * kPad;
  const std::size_t total = std::size_t(g.n[0]) * g.n[1] * g.n[2];
  const double far = std::numeric_limits<double>::infinity();
  g.phi.assign(total, far);
  std::vector<int> closest(total, -1);
  auto idx = [&](int i, int j, int k) { return (std::size_t(k) * g.n[1] + j) * g.n[0] + i; };
  auto node = [&](int i, int j, int k) { return Eigen::Vector3d(g.origin + g.dx * Eigen::Vector3d(i, j, k)); };
  auto tri = [&](int f, int c) { return Eigen::Vector3d(V.row(F(f, c)).transpose()); };
  auto dist = [&](int f, const Eigen::Vector3d& p) { return (p - closest_on_triangle(p, tri(f, 0), tri(f, 1), tri(f, 2))).norm(); };

  // 1. Exact distances in a band of kBand cells around each triangle; crossings of the x lines.
  std::vector<int> crossings(total, 0);
  for (int f = 0; f < F.rows(); ++f) {
    int b0[3], b1[3];
    for (int a = 0; a < 3; ++a) {
      const double mn = std::min({V(F(f, 0), a), V(F(f, 1), a), V(F(f, 2), a)});
      const double mx = std::max({V(F(f, 0), a), V(F(f, 1), a), V(F(f, 2), a)});
      b0[a] = std::clamp(static_cast<int>(std::floor((mn - g.origin(a)) / g.dx)) - kBand, 0, g.n[a] - 1);
      b1[a] = std::clamp(static_cast<int>(std::ceil((mx - g.origin(a)) / g.dx)) + kBand, 0, g.n[a] - 1);
    }
    for (int k = b0[2]; k <= b1[2]; ++k)
      for (int j = b0[1]; j <= b1[1]; ++j)
        for (int i = b0[0]; i <= b1[0]; ++i) {
          const double d = dist(f, node(i, j, k));
          if (d < g.phi[idx(i, j, k)]) g.phi[idx(i, j, k)] = d, closest[idx(i, j, k)] = f;
        }
    // Where the x line through node (., j, k) crosses the triangle: count it at the first node
    // at or beyond the crossing.
    for (int k = b0[2]; k <= b1[2]; ++k)
      for (int j = b0[1]; j <= b1[1]; ++j) {
        const Eigen::Vector3d p = node(0, j, k);
        double a, b, c;
        if (!in_triangle_2d(p.y(), p.z(), V(F(f, 0), 1), V(F(f, 0), 2), V(F(f, 1), 1), V(F(f, 1), 2),
                            V(F(f, 2), 1), V(F(f, 2), 2), a, b, c))
          continue;
        const double x = a * V(F(f, 0), 0) + b * V(F(f, 1), 0) + c * V(F(f, 2), 0);
        const int i = std::max(0, static_cast<int>(std::ceil((x - g.origin.x()) / g.dx)));
        if (i < g.n[0]) ++crossings[idx(i, j, k)];
      }
  }
  // 2. Fast sweeping (Zhao 2005, as in SDFGen): each node tries its swept neighbours' closest
  // triangles, in the 8 diagonal orders, twice.
  for (int pass = 0; pass < 2; ++pass)
    for (int s = 0; s < 8; ++s) {
      const int di = s & 1 ? -1 : 1, dj = s & 2 ? -1 : 1, dk = s & 4 ? -1 : 1;
      for (int k = dk > 0 ? 0 : g.n[2] - 1; k >= 0 && k < g.n[2]; k += dk)
        for (int j = dj > 0 ? 0 : g.n[1] - 1; j >= 0 && j < g.n[1]; j += dj)
          for (int i = di > 0 ? 0 : g.n[0] - 1; i >= 0 && i < g.n[0]; i += di) {
            const std::size_t me = idx(i, j, k);
            const int ni[3] = {i - di, i, i}, nj[3] = {j, j - dj, j}, nk[3] = {k, k, k - dk};
            for (int q = 0; q < 3; ++q) {
              if (ni[q] < 0 || ni[q] >= g.n[0] || nj[q] < 0 || nj[q] >= g.n[1] || nk[q] < 0 || nk[q] >= g.n[2]) continue;
              const int f = closest[idx(ni[q], nj[q], nk[q])];
              if (f < 0 || f == closest[me]) continue;
              const double d = dist(f, node(i, j, k));
              if (d < g.phi[me]) g.phi[me] = d, closest[me] = f;
            }
          }
    }
  // 3. Sign: an odd number of crossings before a node along its x line puts it inside.
  for (int k = 0; k < g.n[2]; ++k)
    for (int j = 0; j < g.n[1]; ++j) {
      int count = 0;
      for (int i = 0; i < g.n[0]; ++i) {
        count += crossings[idx(i, j, k)];
        if (count % 2) g.phi[idx(i, j, k)] = -g.phi[idx(i, j, k)];
      }
    }
  grids_.push_back(std::move(g));
  Shape s{Kind::Mesh};
  s.grid = static_cast<int>(grids_.size()) - 1;
  s.friction = friction;
  s.thickness = thickness;
  return add(std::move(s));
}

void Colliders::set_transform(int i, const Eigen::Vector3d& translation, const Eigen::Matrix3d& rotation) {
  check_index(i, "set_transform");
  require(translation.allFinite(), "set_transform: translation must be finite");
  check_rotation("set_transform", rotation);
  shapes_[i].t = translation;
  shapes_[i].R = rotation;
  ++version_;
}

void Colliders::set_friction(int i, double friction) {
  check_index(i, "set_friction");
  check_coefficients("set_friction", friction, 0.0);
  shapes_[i].friction = friction;
  ++version_;
}

double Colliders::grid_spacing(int i) const {
  check_index(i, "grid_spacing");
  return shapes_[i].kind == Kind::Mesh ? grids_[shapes_[i].grid].dx : 0.0;
}

const char* Colliders::kind(int i) const {
  check_index(i, "kind");
  return shapes_[i].kind == Kind::Sphere ? "sphere" : shapes_[i].kind == Kind::Box ? "box" : "mesh";
}

double Colliders::grid_distance(const Grid& g, const Eigen::Vector3d& q, Eigen::Vector3d& n) {
  // Trilinear inside the grid; beyond it, the distance to the grid's box is added (the grid
  // reaches kPad cells past the mesh, so such points are never in contact).
  Eigen::Vector3d u = (q - g.origin) / g.dx;
  const Eigen::Vector3d clamped_u = u.cwiseMax(0.0).cwiseMin(Eigen::Vector3d(g.n[0] - 1, g.n[1] - 1, g.n[2] - 1));
  const double beyond = (u - clamped_u).norm() * g.dx;
  int c[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    c[a] = std::min(static_cast<int>(std::floor(clamped_u(a))), g.n[a] - 2);
    f[a] = clamped_u(a) - c[a];
  }
  double v[2][2][2];
  for (int dk = 0; dk < 2; ++dk)
    for (int dj = 0; dj < 2; ++dj)
      for (int di = 0; di < 2; ++di) v[di][dj][dk] = g.at(c[0] + di, c[1] + dj, c[2] + dk);
  auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
  double x00 = lerp(v[0][0][0], v[1][0][0], f[0]), x10 = lerp(v[0][1][0], v[1][1][0], f[0]);
  double x01 = lerp(v[0][0][1], v[1][0][1], f[0]), x11 = lerp(v[0][1][1], v[1][1][1], f[0]);
  const double y0 = lerp(x00, x10, f[1]), y1 = lerp(x01, x11, f[1]);
  const double d = lerp(y0, y1, f[2]);
  // The interpolant's own gradient.
  Eigen::Vector3d grad;
  grad.z() = y1 - y0;
  grad.y() = lerp(x10 - x00, x11 - x01, f[2]);
  const double gx00 = v[1][0][0] - v[0][0][0], gx10 = v[1][1][0] - v[0][1][0];
  const double gx01 = v[1][0][1] - v[0][0][1], gx11 = v[1][1][1] - v[0][1][1];
  grad.x() = lerp(lerp(gx00, gx10, f[1]), lerp(gx01, gx11, f[1]), f[2]);
  if (beyond > 0.0)
    n = (u - clamped_u).normalized();
  else
    n = grad.squaredNorm() > 0.0 ? grad.normalized() : Eigen::Vector3d(0, 0, 1);
  return d + beyond;
}

double Colliders::local_distance(const Shape& s, const Eigen::Vector3d& q, Eigen::Vector3d& n) const {
  switch (s.kind) {
    case Kind::Sphere: {
      const double r = q.norm();
      n = r > 0.0 ? Eigen::Vector3d(q / r) : Eigen::Vector3d(0, 0, 1);
      return r - s.radius;
    }
    case Kind::Box: {
      const Eigen::Vector3d e = q.cwiseAbs() - s.half;  // per axis: how far past the face
      const Eigen::Vector3d sign = q.unaryExpr([](double x) { return x < 0.0 ? -1.0 : 1.0; });
      if (e.maxCoeff() > 0.0) {
        const Eigen::Vector3d out = e.cwiseMax(0.0).cwiseProduct(sign);
        n = out.normalized();
        return out.norm();
      }
      int axis;
      const double d = e.maxCoeff(&axis);  // inside: the nearest face
      n = Eigen::Vector3d::Zero();
      n(axis) = sign(axis);
      return d;
    }
    case Kind::Mesh:
      return grid_distance(grids_[s.grid], q, n);
  }
  return std::numeric_limits<double>::infinity();
}

ColliderHit Colliders::query_one(int i, const Eigen::Vector3d& p) const {
  const Shape& s = shapes_[i];
  Eigen::Vector3d n;
  const double d = local_distance(s, s.R.transpose() * (p - s.t), n);
  ColliderHit h;
  h.distance = d - s.thickness;
  h.normal = s.R * n;
  h.friction = s.friction;
  h.index = i;
  return h;
}

ColliderHit Colliders::query(const Eigen::Vector3d& p) const {
  ColliderHit best;
  best.distance = std::numeric_limits<double>::infinity();
  for (int i = 0; i < size(); ++i) {
    const ColliderHit h = query_one(i, p);
    if (h.distance < best.distance) best = h;
  }
  return best;
}

void ColliderMotion::update(const Colliders& colliders, double dt) {
  const int n = colliders.size();
  before_ = last_;
  last_.resize(n);
  moving_.assign(n, 0);
  dt_ = dt;
  for (int i = 0; i < n; ++i) {
    const Pose now{colliders.rotation(i), colliders.translation(i)};
    // Bitwise comparison: a collider that did not move has exactly zero velocity, so a scene
    // with still colliders runs as it did before velocities were taken into account.
    if (i < static_cast<int>(before_.size()))
      moving_[i] = !(now.R.array() == before_[i].R.array()).all() || !(now.t.array() == before_[i].t.array()).all();
    last_[i] = now;
  }
}

Eigen::Vector3d ColliderMotion::velocity(int i, const Eigen::Vector3d& p) const {
  if (i < 0 || i >= static_cast<int>(moving_.size()) || !moving_[i]) return Eigen::Vector3d::Zero();
  // Where the collider's point now at p was one step ago: its local coordinates, then the old pose.
  const Eigen::Vector3d local = last_[i].R.transpose() * (p - last_[i].t);
  const Eigen::Vector3d was = before_[i].R * local + before_[i].t;
  return (p - was) / dt_;
}

}  // namespace thinburn
