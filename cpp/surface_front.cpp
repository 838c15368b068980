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
      const Vec3 w = onto_plane(sc.positions()[q] - src, sc.normals()[q]);
      offer(q, Candidate{t0 + travel(s.v, s.e, w), t0, w});
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
    Candidate best{kInf, 0.0, Vec3::Zero()};
    update_from(x, cell, sx, &best);
    // Causality, also when the speed law changed between calls.
    if (best.t < arrival_[cell]) best.t = arrival_[cell];
    offer(x, best);
  }
}

// Candidates for x from the newly accepted neighbour c: the straight edge c -> x, and every
// triangle (x, c, b) of x's fan. The edge candidate keeps c's virtual source (a corner as a
// new point source would make the factored interpolation downstream undershoot: tau far
// from 1 between a cell and its neighbours).
void SurfaceFront::update_from(int x, int c, const SurfaceSpeed& sx, Candidate* best) const {
  const SurfaceCells& sc = *cells_;
  const Vec3& nx = sc.normals()[x];
  const Vec3 cx = sc.positions()[x] - sc.positions()[c];
  const double te = arrival_[c] + travel(sx.v, sx.e, cx);
  if (te < best->t) *best = Candidate{te, ts_[c], onto_plane(cx, nx) + transport(w_[c], sc.normals()[c], nx)};
  for (int j = sc.fan_offset()[x]; j < sc.fan_offset()[x + 1]; ++j) {
    const auto& t = sc.triangles()[sc.fan_index()[j]];
    if (t[0] != c && t[1] != c && t[2] != c) continue;
    const int b = t[0] != x && t[0] != c ? t[0] : t[1] != x && t[1] != c ? t[1] : t[2];
    triangle_update(x, c, b, state_[b] == 2, sx, best);
  }
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
  const Vec3 y = p.pa + lam * p.q, d1 = y - p.s, d2 = p.px - y;
  const double leg = (d2.norm() - p.e.dot(d2)) / p.W;
  if (!p.factored) return p.Ta + lam * p.dT + leg;
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

// Huygens update of x over the edge (a, b) of triangle (x, a, b), in the triangle's plane.
// The virtual source s of a reference vertex (a, and b when accepted) is unfolded into the
// plane; with tau = (T - t_s) / T0 at both ends (T0 = travel from s), minimise over y on ab
//   g(lambda) = t_s + T0(y) tau(lambda) + travel(y -> x),  tau linear in lambda.
// In a uniform medium tau = 1 and g is minimal where y lies on the segment s -> x: T(x) =
// t_s + travel(s -> x), exact in the unfolding. With b not accepted yet, a's front is
// extended through the triangle only when the ray s -> x crosses the edge ab (obtuse
// corners: x accepted before b would otherwise get the edge-only time).
void SurfaceFront::triangle_update(int x, int a, int b, bool b_known, const SurfaceSpeed& sx,
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
    if (t < best->t) *best = Candidate{t, ts_[ref], transport(onto_plane(px - s, nt), nt, sc.normals()[x])};
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
