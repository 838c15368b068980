#include "surface_front.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Geometry>

namespace thinburn {
namespace {

using Vec3 = Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Later {
  template <class E>
  bool operator()(const E& a, const E& b) const {
    return a.t > b.t || (a.t == b.t && a.cell > b.cell);
  }
};

// Travel time along the straight (unfolded) segment d at the speed law (v, e): the focus
// ellipse's (|d| - e.d) / (v (1 - |e|^2)); |d| / v when isotropic.
double travel(double v, const Vec3& e, const Vec3& d) {
  return (d.norm() - e.dot(d)) / (v * (1.0 - e.squaredNorm()));
}

// Rotate a tangent vector from the plane normal to n1 into the plane normal to n2 (minimal
// rotation, Rodrigues), keeping its length: the unfolding of one tangent plane onto another.
// Sign-agnostic in n1, so inconsistently oriented normals do no harm.
Vec3 transport(const Vec3& w, Vec3 n1, const Vec3& n2) {
  if (n1.dot(n2) < 0.0) n1 = -n1;
  const double c = n1.dot(n2);
  const Vec3 k = n1.cross(n2);
  Vec3 r = w * c + k.cross(w) + k * (k.dot(w) / (1.0 + c));
  r -= r.dot(n2) * n2;
  const double len = r.norm(), want = w.norm();
  return len > 0.0 ? Vec3(r * (want / len)) : r;
}

// The part of d in the plane normal to n, scaled back to |d| (a chord laid onto the plane).
Vec3 onto_plane(const Vec3& d, const Vec3& n) {
  Vec3 t = d - d.dot(n) * n;
  const double len = t.norm();
  return len > 0.0 ? Vec3(t * (d.norm() / len)) : t;
}

// A ray continuing from a cell within this cosine (about 11 degrees) of its direction
// there goes straight on; a sharper bend makes the cell a secondary source (a corner).
constexpr double kStraight = 0.98;

}  // namespace

SurfaceFront::SurfaceFront(std::shared_ptr<const SurfaceCells> cells, const SurfaceFrontOptions& options)
    : cells_(std::move(cells)), opt_(options), t_done_(-kInf) {
  if (!cells_) throw std::invalid_argument("cells must not be null");
  if (!(std::isfinite(options.init_radius) && options.init_radius >= 0.0))
    throw std::invalid_argument("init_radius must be finite and >= 0");
  const std::size_t n = cells_->size();
  state_.assign(n, 0);
  tent_.assign(n, kInf);
  arrival_.assign(n, kInf);
  ts_.assign(n, kInf);
  kappa_.assign(n, 0.0);
  w_.assign(n, Vec3::Zero());
  stamp_.assign(n, 0);
}

bool SurfaceFront::accepted(int cell) const {
  if (cell < 0 || cell >= cells_->size()) throw std::invalid_argument("cell index out of range");
  return state_[cell] == 2;
}

void SurfaceFront::check_ignite(double t0) const {
  if (!std::isfinite(t0)) throw std::invalid_argument("t0 must be finite");
  if (t0 < t_done_)
    throw std::invalid_argument("t0 = " + std::to_string(t0) +
                                " is earlier than the time already advanced to (" +
                                std::to_string(t_done_) + ")");
}

void SurfaceFront::offer(int cell, const Candidate& c) {
  if (!(c.t < tent_[cell])) return;
  tent_[cell] = c.t;
  ts_[cell] = c.ts;
  w_[cell] = c.w;
  kappa_[cell] = c.kappa;
  if (state_[cell] == 0) {
    state_[cell] = 1;
    ++n_trial_;
  }
  heap_.push_back({c.t, cell});
  std::push_heap(heap_.begin(), heap_.end(), Later());
}

void SurfaceFront::ignite_cell(int cell, double t0, const SurfaceSpeedFn& speed) {
  if (cell < 0 || cell >= cells_->size()) throw std::invalid_argument("cell index out of range");
  ignite_point(cells_->positions()[cell], t0, speed);
}

// Direct times t0 + travel(chord) on the cells within init_radius * spacing of the source,
// reached from its cell over cells that can burn. Chord and geodesic differ by O(d^3 K),
// far below the marching error at these distances.
void SurfaceFront::ignite_point(const Vec3& p, double t0, const SurfaceSpeedFn& speed) {
  check_ignite(t0);
  if (!p.allFinite()) throw std::invalid_argument("point must be finite");
  const SurfaceCells& sc = *cells_;
  const int c = sc.nearest(p);
  const Vec3& nc = sc.normals()[c];
  const Vec3 src = p - (p - sc.positions()[c]).dot(nc) * nc;  // onto the cell's tangent plane
  if (!(speed(c).v > 0.0)) return;
  const double radius = opt_.init_radius * sc.spacing();
  ++stamp_id_;
  flood_.assign(1, c);
  stamp_[c] = stamp_id_;
  for (std::size_t i = 0; i < flood_.size(); ++i) {
    const int q = flood_[i];
    if (state_[q] != 2) {
      const SurfaceSpeed s = speed(q);
      // The chord to the source, lengthened to the arc it subtends: phi, the angle between
      // the two normals, is the arc's turning (exact on spheres and across cylinders).
      const Vec3 chord = sc.positions()[q] - src;
      const double phi = std::acos(std::clamp(std::abs(sc.normals()[q].dot(nc)), 0.0, 1.0));
      const double arc = phi > 1e-8 ? 0.5 * phi / std::sin(0.5 * phi) : 1.0;
      const Vec3 w = onto_plane(chord, sc.normals()[q]) * arc;
      const double len = w.norm();
      offer(q, Candidate{t0 + travel(s.v, s.e, w), t0, w, len > 0.0 ? 1.0 / len : kInf});
    }
    for (int j = sc.nbr_offset()[q]; j < sc.nbr_offset()[q + 1]; ++j) {
      const int n = sc.nbr_index()[j];
      if (stamp_[n] == stamp_id_ || (sc.positions()[n] - src).norm() > radius) continue;
      stamp_[n] = stamp_id_;
      if (speed(n).v > 0.0) flood_.push_back(n);
    }
  }
}

const std::vector<int>& SurfaceFront::advance(double t_end, const SurfaceSpeedFn& speed) {
  if (std::isnan(t_end)) throw std::invalid_argument("t_end must not be NaN");
  accepted_now_.clear();
  while (!heap_.empty() && heap_.front().t <= t_end) {
    const Entry e = heap_.front();
    std::pop_heap(heap_.begin(), heap_.end(), Later());
    heap_.pop_back();
    if (state_[e.cell] == 2 || e.t != tent_[e.cell]) continue;  // stale entry
    state_[e.cell] = 2;
    arrival_[e.cell] = e.t;
    --n_trial_;
    accepted_now_.push_back(e.cell);
    update_neighbours(e.cell, speed);
  }
  t_done_ = std::max(t_done_, t_end);
  return accepted_now_;
}

void SurfaceFront::update_neighbours(int cell, const SurfaceSpeedFn& speed) {
  const SurfaceCells& sc = *cells_;
  for (int j = sc.nbr_offset()[cell]; j < sc.nbr_offset()[cell + 1]; ++j) {
    const int x = sc.nbr_index()[j];
    if (state_[x] == 2) continue;
    const SurfaceSpeed sx = speed(x);
    if (!(sx.v > 0.0)) continue;
    Candidate best{kInf, 0.0, Vec3::Zero(), 0.0};
    update_from(x, cell, sx, &best);
    // Causality, also when the speed law changed between calls.
    if (best.t < arrival_[cell]) best.t = arrival_[cell];
    offer(x, best);
  }
}

// Candidates for x from the newly accepted neighbour c: the straight edge c -> x, and every
// triangle (x, c, b) of x's fan. With a drive the edge candidate keeps c's virtual source (a
// corner as a new point source would make the factored interpolation downstream undershoot:
// tau far from 1 between neighbours). Isotropic, it records the edge's own direction (the
// ray's, which the curvature model's centres are placed along) and, where the ray bends at c
// (round a hole's corner), the circle about c that the front then is.
void SurfaceFront::update_from(int x, int c, const SurfaceSpeed& sx, Candidate* best) const {
  const SurfaceCells& sc = *cells_;
  const Vec3& nx = sc.normals()[x];
  const Vec3 cx = sc.positions()[x] - sc.positions()[c];
  const double te = arrival_[c] + travel(sx.v, sx.e, cx);
  const bool iso = sx.e.isZero();
  if (te < best->t) {
    const double K = 0.5 * (sc.gauss_curvature()[x] + sc.gauss_curvature()[c]);
    const Vec3 wc = transport(w_[c], sc.normals()[c], nx);
    const Vec3 leg = onto_plane(cx, nx);
    const double l = leg.norm();
    if (!iso || !(l > 0.0)) {
      *best = Candidate{te, ts_[c], leg + wc, riccati(kappa_[c], l, K)};
    } else {
      const double wl = wc.norm();
      const bool straight = wl > 0.0 && wc.dot(leg) > kStraight * wl * l;
      const double k = straight ? riccati(kappa_[c], l, K) : riccati(kInf, l, K);
      *best = Candidate{te, ts_[c], leg * ((wl + l) / l), k};
    }
  }
  for (int j = sc.fan_offset()[x]; j < sc.fan_offset()[x + 1]; ++j) {
    const auto& t = sc.triangles()[sc.fan_index()[j]];
    if (t[0] != c && t[1] != c && t[2] != c) continue;
    const int b = t[0] != x && t[0] != c ? t[0] : t[1] != x && t[1] != c ? t[1] : t[2];
    if (iso)
      curved_update(x, c, b, state_[b] == 2, sx, best);
    else
      drive_update(x, c, b, state_[b] == 2, sx, best);
  }
}

// Whether every accepted neighbour c of x could lie on a's front circle: radii differing by
// at most twice their distance (one point source gives at most once).
bool SurfaceFront::radius_consistent(int x, int a) const {
  const SurfaceCells& sc = *cells_;
  const double ka = kappa_[a];
  if (!(ka > 0.0)) return false;
  const double da = 1.0 / ka;
  for (int j = sc.nbr_offset()[x]; j < sc.nbr_offset()[x + 1]; ++j) {
    const int c = sc.nbr_index()[j];
    if (c == a || state_[c] != 2) continue;
    const double dc = kappa_[c] > 0.0 ? 1.0 / kappa_[c] : kInf;
    if (!(std::abs(da - dc) <= 2.0 * (sc.positions()[c] - sc.positions()[a]).norm())) return false;
  }
  return true;
}

// The front's geodesic curvature after travelling `length` along a ray over a surface of
// Gaussian curvature `gauss`: d kappa / ds = -kappa^2 - K (exact for K = 0: a circle's
// 1 / (r + s); cot(s / R) / R on a sphere). Converging fronts are clamped at 2 / spacing,
// where the cells cannot resolve the focus anyway.
double SurfaceFront::riccati(double kappa, double length, double gauss) const {
  const double floor = -2.0 / cells_->spacing();
  if (std::isinf(kappa) && kappa > 0.0) return std::max(1.0 / length - gauss * length, floor);  // from the source point
  const double grow = 1.0 + kappa * length;
  const double k = (grow > 0.25 ? kappa / grow : floor) - gauss * length;
  return std::max(k, floor);
}

namespace {

// g(lambda) = A(lambda) + travel(y -> x), y = pa + lambda q, with the time at y either
// factored, A = ts + (tau_a + lambda dtau) T0(y - s), or linear, A = Ta + lambda dT.
struct EdgeProblem {
  Vec3 pa, q, px, s, e;
  double W;  // v (1 - |e|^2)
  bool factored;
  double ts, tau_a, dtau;  // factored
  double Ta, dT;           // linear
};

double edge_value(const EdgeProblem& p, double lam) {
  const Vec3 y = p.pa + lam * p.q, d2 = p.px - y;
  const double leg = (d2.norm() - p.e.dot(d2)) / p.W;
  if (!p.factored) return p.Ta + lam * p.dT + leg;
  const Vec3 d1 = y - p.s;
  return p.ts + (p.tau_a + lam * p.dtau) * (d1.norm() - p.e.dot(d1)) / p.W + leg;
}

// Safeguarded Newton on g'(lambda) = 0 over [0, 1] (g is convex for the linear form and
// nearly so for the factored one), from lam.
double edge_minimum(const EdgeProblem& p, double lam) {
  const double qq = p.q.squaredNorm(), eq = p.e.dot(p.q);
  double lo = 0.0, hi = 1.0;
  lam = std::isfinite(lam) ? std::clamp(lam, 0.0, 1.0) : 0.5;
  for (int it = 0; it < 30; ++it) {
    const Vec3 y = p.pa + lam * p.q, d2 = p.px - y;
    const double n2 = d2.norm();
    if (!(n2 > 0.0)) break;
    const double q2 = d2.dot(p.q) / n2;
    double gp = -(q2 - eq) / p.W, gpp = (qq - q2 * q2) / (n2 * p.W);
    if (p.factored) {
      const Vec3 d1 = y - p.s;
      const double n1 = d1.norm();
      if (!(n1 > 0.0)) break;
      const double q1 = d1.dot(p.q) / n1, tau = p.tau_a + lam * p.dtau;
      const double F1 = (n1 - p.e.dot(d1)) / p.W, F1p = (q1 - eq) / p.W, F1pp = (qq - q1 * q1) / (n1 * p.W);
      gp += p.dtau * F1 + tau * F1p;
      gpp += 2.0 * p.dtau * F1p + tau * F1pp;
    } else {
      gp += p.dT;
    }
    if (gp > 0.0) hi = lam; else lo = lam;
    double next = gpp > 0.0 ? lam - gp / gpp : 0.5 * (lo + hi);
    if (!(next >= lo && next <= hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - lam) < 1e-12 || hi - lo < 1e-12;
    lam = next;
    if (done) break;
  }
  return lam;
}

// Factored interpolation is trusted only while both ends agree on the source (tau within
// this fraction of each other); otherwise (fronts from different sources colliding, a
// corner's shadow) T is interpolated linearly, which is first order but never undershoots
// a convex T.
constexpr double kTauAgree = 0.05;

}  // namespace

namespace {

// Minimal in-plane geometry of the update of x over the edge (a, b): the triangle's unit
// normal, the edge's unit direction u and length L, and p, the in-plane unit vector
// perpendicular to the edge pointing to x's side.
struct EdgeFrame {
  Vec3 nt, u, p;
  double L;
};

bool edge_frame(const Vec3& px, const Vec3& pa, const Vec3& pb, EdgeFrame* f) {
  f->nt = (pa - px).cross(pb - px);
  const double nlen = f->nt.norm();
  if (!(nlen > 1e-12 * (pa - px).squaredNorm() + 1e-300)) return false;  // degenerate
  f->nt /= nlen;
  f->L = (pb - pa).norm();
  f->u = (pb - pa) / f->L;
  f->p = f->nt.cross(f->u);
  if (f->p.dot(px - pa) < 0.0) f->p = -f->p;
  return true;
}

// Where the line through s and x crosses the line a + lambda (b - a), as lambda.
double crossing(const Vec3& s, const Vec3& px, const Vec3& pa, const Vec3& pb, const Vec3& nt) {
  const Vec3 d = px - s, q = pb - pa;
  const double den = q.cross(d).dot(nt);
  return std::abs(den) > 0.0 ? (s - pa).cross(d).dot(nt) / den : kInf;
}

// Directions of two fronts agree enough to share one curvature model (about 45 degrees).
constexpr double kDirAgree = 0.7;
// Cosine of the corner angle at x above which (narrower corners) a lone end's circle is
// not extended to x: measured against 0, 0.05, 0.17, 0.26, 0.5 (docs/surface_front.md).
constexpr double kWideCorner = 0.1;

}  // namespace

// Huygens update of x over the edge (a, b) of triangle (x, a, b), in the triangle's plane.
// The virtual source s of a reference vertex (a, and b when accepted) is unfolded into the
// plane; with tau = (T - t_s) / T0 at both ends (T0 = travel from s), minimise over y on ab
//   g(lambda) = t_s + T0(y) tau(lambda) + travel(y -> x),  tau linear in lambda.
// In a uniform medium tau = 1 and g is minimal where y lies on the segment s -> x: T(x) =
// t_s + travel(s -> x), exact in the unfolding. With b not accepted yet, a's front is
// extended through the triangle only when the ray s -> x crosses the edge ab (obtuse
// corners: x accepted before b would otherwise get the edge-only time).
void SurfaceFront::drive_update(int x, int a, int b, bool b_known, const SurfaceSpeed& sx,
                                   Candidate* best) const {
  const SurfaceCells& sc = *cells_;
  const Vec3& px = sc.positions()[x];
  const Vec3& pa = sc.positions()[a];
  const Vec3& pb = sc.positions()[b];
  Vec3 nt = (pa - px).cross(pb - px);
  const double nlen = nt.norm();
  if (!(nlen > 1e-12 * (pa - px).squaredNorm() + 1e-300)) return;  // degenerate triangle
  nt /= nlen;
  EdgeProblem p;
  p.pa = pa;
  p.q = pb - pa;
  p.px = px;
  p.e = sx.e.isZero() ? Vec3(Vec3::Zero()) : transport(sx.e, sc.normals()[x], nt);
  p.W = sx.v * (1.0 - p.e.squaredNorm());
  auto source_of = [&](int r) { return Vec3(sc.positions()[r] - transport(w_[r], sc.normals()[r], nt)); };
  auto T0 = [&](const Vec3& d) { return (d.norm() - p.e.dot(d)) / p.W; };
  auto take = [&](double t, int ref, const Vec3& s) {
    if (t < best->t) *best = Candidate{t, ts_[ref], transport(onto_plane(px - s, nt), nt, sc.normals()[x]), 1.0 / std::max((px - s).norm(), 1e-300)};
  };
  if (!b_known) {
    const Vec3 s = source_of(a);
    const double T0a = T0(pa - s);
    if (!(T0a > 0.0)) return;
    // Where the ray s -> x crosses the line a + lambda q.
    const Vec3 d = px - s;
    const double den = p.q.cross(d).dot(nt);
    const double lam = std::abs(den) > 0.0 ? (s - pa).cross(d).dot(nt) / den : -1.0;
    if (!(lam >= -1e-9 && lam <= 1.0 + 1e-9)) return;
    const Vec3 y = pa + std::clamp(lam, 0.0, 1.0) * p.q;
    if ((y - s).dot(d) <= 0.0 || (y - s).squaredNorm() > d.squaredNorm()) return;
    take(ts_[a] + (arrival_[a] - ts_[a]) / T0a * T0(y - s) + T0(px - y), a, s);
    return;
  }
  // Linear interpolation of T: always a candidate (safe), keeping the earlier end's source.
  const int early = arrival_[a] <= arrival_[b] ? a : b;
  p.factored = false;
  p.Ta = arrival_[a];
  p.dT = arrival_[b] - arrival_[a];
  const double lam_lin = edge_minimum(p, 0.5);
  take(edge_value(p, lam_lin), early, source_of(early));
  p.factored = true;
  for (int ref : {a, b}) {
    const Vec3 s = source_of(ref);
    const double T0a = T0(pa - s), T0b = T0(pb - s);
    if (!(T0a > 0.0) || !(T0b > 0.0)) continue;  // a vertex is the source point itself
    p.s = s;
    p.ts = ts_[ref];
    p.tau_a = (arrival_[a] - p.ts) / T0a;
    const double tau_b = (arrival_[b] - p.ts) / T0b;
    if (!(std::abs(tau_b - p.tau_a) <= kTauAgree * std::max(std::abs(p.tau_a), std::abs(tau_b)))) continue;
    p.dtau = tau_b - p.tau_a;
    const Vec3 d = px - s;
    const double den = p.q.cross(d).dot(nt);
    const double lam0 = std::abs(den) > 0.0 ? (s - pa).cross(d).dot(nt) / den : 0.5;
    take(edge_value(p, edge_minimum(p, lam0)), ref, s);
  }
}


// Isotropic update of x over the edge (a, b), in the triangle's plane, with the front near
// the edge modelled as a circle of the cells' curvature (second order in the front's shape,
// where plain fast marching assumes a plane): the circle's centre s is placed so that it
// reproduces T(a) and T(b); T(x) = T + (|x - s| - D) / v on it. The curvature itself is
// carried along the rays by the Riccati equation with the surface's Gaussian curvature, so
// that positive curvature (spheres) bends the rays together as it should; the plane
// unfolding alone (D = distance to the source) undershoots there by about h d / 40 per unit
// distance. The circle's centre lies on the line through x and its crossing of the edge
// must lie on the edge (else another triangle owns the ray). With b not yet accepted, a's
// own circle is extended across the edge when its ray to x crosses it.
void SurfaceFront::curved_update(int x, int a, int b, bool b_known, const SurfaceSpeed& sx,
                                 Candidate* best) const {
  const SurfaceCells& sc = *cells_;
  const Vec3& px = sc.positions()[x];
  const Vec3& pa = sc.positions()[a];
  const Vec3& pb = sc.positions()[b];
  EdgeFrame f;
  if (!edge_frame(px, pa, pb, &f)) return;
  const double v = sx.v;
  const auto& K = sc.gauss_curvature();
  auto dir_of = [&](int r) {
    const Vec3 g = transport(w_[r], sc.normals()[r], f.nt);
    const double len = g.norm();
    return len > 0.0 ? Vec3(g / len) : Vec3(Vec3::Zero());
  };
  const Candidate none{kInf, 0.0, Vec3::Zero(), 0.0};
  // T on the circle (centre s, signed curvature 1/D) whose ray reaches x across the edge
  // at lambda; `none` if it does not.
  auto circle = [&](double t, const Vec3& s, double lam, bool diverging, double gauss) {
    if (!(lam >= -1e-9 && lam <= 1.0 + 1e-9) || !std::isfinite(t)) return none;
    const Vec3 y = pa + std::clamp(lam, 0.0, 1.0) * (pb - pa);
    const double ry = (y - s).norm(), rx = (px - s).norm();
    if (!(ry > 0.0) || !(rx > 0.0)) return none;
    // The ray must reach x through the edge: y between s and x (spreading), or y behind x
    // as seen from the focus s (converging).
    if (diverging ? ((y - s).dot(px - s) <= 0.0 || ry > rx * (1.0 + 1e-12)) : (y - px).dot(s - px) > 0.0) return none;
    const Vec3 g = diverging ? Vec3((px - s) / rx) : Vec3((s - px) / rx);
    const double k = riccati(diverging ? 1.0 / ry : -1.0 / ry, (px - y).norm(), gauss);
    const Vec3 w = transport(g, f.nt, sc.normals()[x]) * std::max(t - ts_[a], 0.0) * v;
    return Candidate{t, t - w.norm() / v, w, k};
  };
  auto take = [&](const Candidate& c) {
    if (c.t < best->t) *best = c;
  };
  // One end's own circle extended to x, when its ray to x crosses the edge.
  auto extend = [&](int r) {
    const double kr = kappa_[r];
    if (!(kr > 0.0)) return none;
    const double D = 1.0 / kr;
    const Vec3& pr = sc.positions()[r];
    const Vec3 s = pr - dir_of(r) * D;
    if ((px - s).dot(pr - s) <= 0.0) return none;
    return circle(arrival_[r] + ((px - s).norm() - D) / v, s, crossing(s, px, pa, pb, f.nt), true,
                  (K[x] + K[r]) / 2.0);
  };
  if (!b_known) {
    // x is due before b only across a wide corner at x (about 84 degrees or more): then a's
    // circle alone, unless x's accepted cells hold fronts of other radii (a shadow line).
    // Elsewhere b comes first and the two-point update follows; extending there too let
    // chains of extensions carry a circle, unchecked, far past where its centre is seen:
    // into a hole's shadow (5.4 % early behind a square hole), along a sphere's equator.
    if ((pa - px).normalized().dot((pb - px).normalized()) > kWideCorner) return;
    if (!radius_consistent(x, a)) return;
    take(extend(a));
    return;
  }
  const double gauss = (K[x] + K[a] + K[b]) / 3.0;
  // Linear interpolation of T along the edge: first order, never below a convex T.
  auto lin = [&]() {
    EdgeProblem lp;
    lp.pa = pa, lp.q = pb - pa, lp.px = px, lp.e = Vec3::Zero(), lp.W = v;
    lp.factored = false, lp.Ta = arrival_[a], lp.dT = arrival_[b] - arrival_[a];
    const double lam = edge_minimum(lp, 0.5);
    const double t = edge_value(lp, lam);
    if (t < best->t) {
      const Vec3 y = pa + lam * lp.q;
      const int early = arrival_[a] <= arrival_[b] ? a : b;
      const double kk = lam <= 0.0 ? kappa_[a] : lam >= 1.0 ? kappa_[b] : (1.0 - lam) * kappa_[a] + lam * kappa_[b];
      const Vec3 w = transport(onto_plane(px - y, f.nt).normalized(), f.nt, sc.normals()[x]) *
                     std::max(t - ts_[early], 0.0) * v;
      *best = Candidate{t, ts_[early], w, riccati(kk, (px - y).norm(), gauss)};
    }
  };
  const Vec3 ga = dir_of(a), gb = dir_of(b);
  if (!(ga.dot(gb) > kDirAgree)) {
    // Fronts from different directions meet here (a collision line): T has a ridge along
    // the edge, and both the linear and the two-point models would cut below it. Each
    // front holds on its own side: the earlier of the two.
    take(extend(a));
    take(extend(b));
    return;
  }
  lin();
  const double c = (arrival_[b] - arrival_[a]) * v / f.L;  // n . u of the front's normal n
  if (!(std::abs(c) < 1.0)) return;
  const Vec3 n = c * f.u + std::sqrt(1.0 - c * c) * f.p;
  double kap = 0.0;
  if (n.dot(ga) > kDirAgree && n.dot(gb) > kDirAgree) {
    const double ka = kappa_[a], kb = kappa_[b];
    // One circle through both ends only if their radii could be one front's: two points of
    // a circle differ in radius by at most the edge (a front lit directly next to one bent
    // round a corner, tangent to it at the shadow line, would make the circle cut below
    // both). Nearly plane fronts agree whatever their signs.
    const bool flat = std::max(std::abs(ka), std::abs(kb)) * f.L < 0.05;
    const bool same = ka * kb > 0.0 && std::abs(1.0 / ka - 1.0 / kb) <= 2.0 * f.L;
    if (!flat && !same) {
      // A shadow line: a front seen directly beside one bent round a corner, tangent to
      // it. The bent one is the later of the two wherever both reach, and the direct one
      // must not be carried into the shadow: the later of the two, and only if both reach.
      const Candidate ea = extend(a), eb = extend(b);
      if (ea.t < kInf && eb.t < kInf) take(ea.t > eb.t ? ea : eb);
      return;
    }
    // Spreading fronts: average the radii (exact for a point source in the plane).
    kap = ka > 0.0 && kb > 0.0 ? 2.0 / (1.0 / ka + 1.0 / kb) : 0.5 * (ka + kb);
  }
  const double Tbar = 0.5 * (arrival_[a] + arrival_[b]);
  const Vec3 m = 0.5 * (pa + pb);
  if (std::abs(kap) * f.L < 1e-7) {  // a plane front
    const Vec3 s = px - n;  // any point behind x on its ray
    take(circle(Tbar + n.dot(px - m) / v, s, crossing(s, px, pa, pb, f.nt), true, gauss));
    return;
  }
  const double D = 1.0 / std::abs(kap);
  if (!(D > 0.5 * f.L)) return;
  const double hgt = std::sqrt((1.0 - c * c) * (D * D - 0.25 * f.L * f.L));
  if (kap > 0.0) {
    const Vec3 s = pa + (0.5 * f.L - c * D) * f.u - hgt * f.p;
    take(circle(Tbar + ((px - s).norm() - D) / v, s, crossing(s, px, pa, pb, f.nt), true, gauss));
  } else {
    const Vec3 s = pa + (0.5 * f.L + c * D) * f.u + hgt * f.p;
    if ((s - px).dot(f.p) <= 0.0) return;  // x lies beyond the focus
    take(circle(Tbar + (D - (px - s).norm()) / v, s, crossing(s, px, pa, pb, f.nt), false, gauss));
  }
}

std::vector<double> surface_arrival_times(std::shared_ptr<const SurfaceCells> cells,
                                          const std::vector<double>& speed,
                                          const std::vector<Eigen::Vector3d>& drive,
                                          const std::vector<Eigen::Vector3d>& points,
                                          const std::vector<double>& t0) {
  if (!cells) throw std::invalid_argument("cells must not be null");
  const std::size_t n = cells->size();
  if (speed.size() != n) throw std::invalid_argument("speed must have one entry per cell");
  if (!drive.empty() && drive.size() != n) throw std::invalid_argument("drive must be empty or one per cell");
  if (points.size() != t0.size()) throw std::invalid_argument("sources and t0 must have the same length");
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(speed[i]) && speed[i] >= 0.0)) throw std::invalid_argument("speed must be finite and >= 0");
    if (!drive.empty() && !(drive[i].allFinite() && drive[i].squaredNorm() < 1.0))
      throw std::invalid_argument("drive must be finite with |e| < 1");
  }
  SurfaceFront front(cells);
  const SurfaceSpeedFn fn = [&](int c) {
    return drive.empty() ? SurfaceSpeed{speed[c]} : SurfaceSpeed{speed[c], drive[c]};
  };
  std::vector<std::size_t> order(points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return t0[a] < t0[b]; });
  for (std::size_t i : order) front.ignite_point(points[i], t0[i], fn);
  front.advance(kInf, fn);
  return front.arrival();
}

}  // namespace thinburn
