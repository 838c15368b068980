#include "fire_front.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace thinburn {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool finite_positive(double x) { return std::isfinite(x) && x > 0.0; }

// Min-heap order on (time, cell): ties go to the lower cell index, so runs are deterministic.
struct Later {
  template <class E>
  bool operator()(const E& a, const E& b) const {
    return a.t > b.t || (a.t == b.t && a.cell > b.cell);
  }
};

// 4-neighbours first, then the diagonals.
constexpr int kRingDr[8] = {-1, 1, 0, 0, -1, -1, 1, 1};
constexpr int kRingDc[8] = {0, 0, -1, 1, -1, 1, -1, 1};

double drive_sq(const LocalSpeed& s) { return s.e_row * s.e_row + s.e_col * s.e_col; }

// Root of h(P d + pl) = 1 in d, h(p) = v (e.p + sqrt((1-|e|^2)|p|^2 + (e.p)^2)). Squaring
// gives q(p) = w|p|^2 + 2 e.p / v - 1/v^2 = 0, a quadratic in d. Of its roots on the h = +1
// sheet (1/v - e.p >= 0) the larger is kept: as d grows, p takes the upwind signs (the
// smaller root, if any, has T decreasing away from a neighbour). False if there is none.
bool eikonal_root_scaled(const double P[2], const double pl[2], double iv, const LocalSpeed& s, double* d) {
  const double w = 1.0 - drive_sq(s);
  const double e[2] = {s.e_row, s.e_col};
  const double A = w * (P[0] * P[0] + P[1] * P[1]);
  if (!(A > 0.0)) return false;
  const double B = 2.0 * w * (P[0] * pl[0] + P[1] * pl[1]) + 2.0 * iv * (e[0] * P[0] + e[1] * P[1]);
  const double C = w * (pl[0] * pl[0] + pl[1] * pl[1]) + 2.0 * iv * (e[0] * pl[0] + e[1] * pl[1]) - iv * iv;
  const double disc = B * B - 4.0 * A * C;
  if (!(disc >= 0.0)) return false;
  const double sq = std::sqrt(disc);
  const double hi = B < 0.0 ? (sq - B) / (2.0 * A) : (B + sq > 0.0 ? -2.0 * C / (B + sq) : 0.0);
  const double lo = B >= 0.0 ? -(B + sq) / (2.0 * A) : 2.0 * C / (sq - B);
  auto on_sheet = [&](double x) {
    return iv - (e[0] * (P[0] * x + pl[0]) + e[1] * (P[1] * x + pl[1])) >= -1e-12 * iv;
  };
  if (on_sheet(hi)) {
    *d = hi;
    return true;
  }
  if (on_sheet(lo)) {
    *d = lo;
    return true;
  }
  return false;
}

// The quadratic is solved in scaled variables, by powers of two (exact): d = sd D, and the
// equation, homogeneous of degree 2 in (P, pl, 1/v), divided through by k^2. Unscaled, its
// coefficients go as 1/v^2 and 1/v^4 and over- or underflowed for speeds outside about
// 1e-70..1e80 m/s (the arrival times then came out wrong; r5).
bool eikonal_root(const double P_in[2], const double pl_in[2], const LocalSpeed& s, double* d) {
  const double pm = std::max(std::abs(P_in[0]), std::abs(P_in[1]));
  if (!(pm > 0.0) || !std::isfinite(pm)) return false;
  const double iv_in = 1.0 / s.v;
  if (!(iv_in > 0.0) || !std::isfinite(iv_in)) return false;
  const int ed = std::ilogb(iv_in) - std::ilogb(pm);  // d's scale: 1/v over |P|
  double P[2] = {std::ldexp(P_in[0], ed), std::ldexp(P_in[1], ed)};
  const double big = std::max({std::abs(P[0]), std::abs(P[1]), std::abs(pl_in[0]), std::abs(pl_in[1]), iv_in});
  if (!std::isfinite(big)) return false;
  const int ek = -std::ilogb(big);
  P[0] = std::ldexp(P[0], ek), P[1] = std::ldexp(P[1], ek);
  const double pl[2] = {std::ldexp(pl_in[0], ek), std::ldexp(pl_in[1], ek)};
  const double iv = std::ldexp(iv_in, ek);
  if (!eikonal_root_scaled(P, pl, iv, s, d)) return false;
  *d = std::ldexp(*d, ed);
  return true;
}

// The characteristic direction grad_p h(p) (along p when isotropic).
void characteristic(const double p_in[2], const LocalSpeed& s, double g[2]) {
  if (s.e_row == 0.0 && s.e_col == 0.0) {
    g[0] = p_in[0], g[1] = p_in[1];
    return;
  }
  const double w = 1.0 - drive_sq(s);
  const double e[2] = {s.e_row, s.e_col};
  // Scaled by a power of two (the direction does not change) so that S neither over- nor
  // underflows at extreme speeds.
  const double pm = std::max(std::abs(p_in[0]), std::abs(p_in[1]));
  const int ek = pm > 0.0 && std::isfinite(pm) ? -std::ilogb(pm) : 0;
  const double p[2] = {std::ldexp(p_in[0], ek), std::ldexp(p_in[1], ek)};
  const double ep = e[0] * p[0] + e[1] * p[1];
  const double S = std::sqrt(w * (p[0] * p[0] + p[1] * p[1]) + ep * ep);
  for (int k = 0; k < 2; ++k) g[k] = e[k] + (w * p[k] + ep * e[k]) / S;
}

}  // namespace

double ray_speed(const LocalSpeed& s, double ur, double uc) {
  return s.v * (1.0 - drive_sq(s)) / (1.0 - (s.e_row * ur + s.e_col * uc));
}

double normal_speed(const LocalSpeed& s, double nr, double nc) {
  const double en = s.e_row * nr + s.e_col * nc;
  return s.v * (en + std::sqrt(1.0 - drive_sq(s) + en * en));
}

FireFront::FireFront(int ny, int nx, double dy, double dx, FrontMethod method,
                     const FrontOptions& options)
    : ny_(ny), nx_(nx), dy_(dy), dx_(dx), method_(method), opt_(options), t_done_(-kInf) {
  if (ny < 1 || nx < 1) throw std::invalid_argument("ny, nx: the grid must be at least 1 x 1");
  if (static_cast<long long>(ny) * nx > INT_MAX) throw std::invalid_argument("ny, nx: grid too large");
  if (!finite_positive(dy)) throw std::invalid_argument("dy must be finite and > 0");
  if (!finite_positive(dx)) throw std::invalid_argument("dx must be finite and > 0");
  if (!(std::isfinite(options.init_radius) && options.init_radius >= 0.0))
    throw std::invalid_argument("init_radius must be finite and >= 0");
  const std::size_t n = static_cast<std::size_t>(ny) * nx;
  inside_.assign(n, 1);
  state_.assign(n, 0);
  fixed_.assign(n, 0);
  tent_.assign(n, kInf);
  arrival_.assign(n, kInf);
  tau_.assign(n, kInf);
  label_.assign(n, -1);
  stamp_.assign(n, 0);
  heap_.reserve(4 * static_cast<std::size_t>(ny + nx) + 64);
  if (!cellular()) return;

  auto add = [&](int dr, int dc) {
    Step s{};
    s.dr = dr;
    s.dc = dc;
    const double my = dr * dy_, mx = dc * dx_;
    s.length = std::hypot(my, mx);
    s.ur = my / s.length;
    s.uc = mx / s.length;
    const int ar = std::abs(dr), ac = std::abs(dc);
    if (ar == 1 && ac == 1) {  // diagonal: squeezes between the two orthogonal cells
      s.n_pass = 2;
      s.pass_dr[0] = dr, s.pass_dc[0] = 0;
      s.pass_dr[1] = 0, s.pass_dc[1] = dc;
    } else if (ar == 2 && ac == 1) {  // knight move: its segment crosses both middle cells
      s.n_pass = 2;
      s.need_both = true;
      s.pass_dr[0] = dr / 2, s.pass_dc[0] = 0;
      s.pass_dr[1] = dr / 2, s.pass_dc[1] = dc;
    } else if (ar == 1 && ac == 2) {
      s.n_pass = 2;
      s.need_both = true;
      s.pass_dr[0] = 0, s.pass_dc[0] = dc / 2;
      s.pass_dr[1] = dr, s.pass_dc[1] = dc / 2;
    }
    steps_.push_back(s);
  };
  for (int dr = -2; dr <= 2; ++dr)
    for (int dc = -2; dc <= 2; ++dc) {
      const int ar = std::abs(dr), ac = std::abs(dc);
      if (ar + ac == 0 || (ar == 2 && ac != 1) || (ac == 2 && ar != 1)) continue;
      if ((ar == 2 || ac == 2) && method_ != FrontMethod::Cellular16) continue;
      add(dr, dc);
    }
}

void FireFront::set_inside(const std::vector<std::uint8_t>& inside) {
  if (inside.size() != inside_.size())
    throw std::invalid_argument("inside must have ny*nx = " + std::to_string(inside_.size()) +
                                " entries, got " + std::to_string(inside.size()));
  for (std::size_t i = 0; i < inside.size(); ++i) inside_[i] = inside[i] ? 1 : 0;
}

bool FireFront::can_burn(int cell, const SpeedFn& speed) const {
  return inside_[cell] && speed(cell).v > 0.0;
}

bool FireFront::accepted(int cell) const {
  if (cell < 0 || static_cast<std::size_t>(cell) >= state_.size())
    throw std::invalid_argument("cell index out of range");
  return state_[cell] == 2;
}

void FireFront::push(int cell, double t, double tau, int label) {
  tent_[cell] = t;
  tau_[cell] = tau;
  label_[cell] = label;
  if (state_[cell] == 0) {
    state_[cell] = 1;
    ++n_trial_;
  }
  heap_.push_back({t, cell});
  std::push_heap(heap_.begin(), heap_.end(), Later());
}

void FireFront::accept(int cell, double t) {
  state_[cell] = 2;
  fixed_[cell] = 0;
  arrival_[cell] = t;
  --n_trial_;
  accepted_now_.push_back(cell);
}

void FireFront::ignite(const FrontSource& s, const SpeedFn& speed) {
  if (!std::isfinite(s.t0)) throw std::invalid_argument("t0 must be finite");
  if (s.t0 < t_done_)
    throw std::invalid_argument("t0 = " + std::to_string(s.t0) +
                                " is earlier than the time already advanced to (" +
                                std::to_string(t_done_) + ")");
  if (!(s.row >= -0.5 && s.row <= ny_ - 0.5))
    throw std::invalid_argument("source row must lie in [-0.5, ny - 0.5]");
  if (!(s.col >= -0.5 && s.col <= nx_ - 0.5))
    throw std::invalid_argument("source col must lie in [-0.5, nx - 0.5]");
  const int r = std::clamp(static_cast<int>(std::lround(s.row)), 0, ny_ - 1);
  const int c = std::clamp(static_cast<int>(std::lround(s.col)), 0, nx_ - 1);
  const int cell = r * nx_ + c;
  if (!inside_[cell]) return;
  const LocalSpeed src = speed(cell);
  if (!(src.v > 0.0)) return;
  if (cellular()) {
    if (state_[cell] != 2 && s.t0 < tent_[cell]) push(cell, s.t0, s.t0, -1);
    return;
  }
  ignite_fmm(s, cell, src, speed);
}

// Exact times t0 + distance / ray speed on the cells of a disc around the source, reached
// from the source cell without crossing cells that cannot burn.
void FireFront::ignite_fmm(const FrontSource& s, int cell, const LocalSpeed& src,
                           const SpeedFn& speed) {
  const double radius = opt_.init_radius;
  const int label = static_cast<int>(sources_.size());
  sources_.push_back({s.row, s.col, s.t0, src});
  ++stamp_id_;
  flood_.clear();
  flood_.push_back(cell);
  stamp_[cell] = stamp_id_;
  for (std::size_t i = 0; i < flood_.size(); ++i) {
    const int q = flood_[i], qr = q / nx_, qc = q % nx_;
    const double t = s.t0 + factor(label, q, nullptr, nullptr);
    if (state_[q] != 2 && t < tent_[q]) {
      push(q, t, method_ == FrontMethod::Fmm2 ? 1.0 : t, method_ == FrontMethod::Fmm2 ? label : -1);
      fixed_[q] = 1;
    }
    for (int k = 0; k < 4; ++k) {
      const int nr = qr + kRingDr[k], nc = qc + kRingDc[k];
      if (nr < 0 || nr >= ny_ || nc < 0 || nc >= nx_) continue;
      const int n = nr * nx_ + nc;
      if (stamp_[n] == stamp_id_ || !inside_[n]) continue;
      if (std::hypot(nr - s.row, nc - s.col) > radius) continue;
      stamp_[n] = stamp_id_;
      if (speed(n).v > 0.0) flood_.push_back(n);
    }
  }
}

// Travel time T0 = |d| / ray speed from source `label` to the centre of `cell` (exact for a
// uniform medium), and optionally its gradient.
double FireFront::factor(int label, int cell, double* g_row, double* g_col) const {
  const SourceRec& src = sources_[label];
  const double my = (cell / nx_ - src.row) * dy_, mx = (cell % nx_ - src.col) * dx_;
  const double d = std::hypot(my, mx);
  const double denom = src.s.v * (1.0 - drive_sq(src.s));
  if (g_row) {
    *g_row = d > 0.0 ? (my / d - src.s.e_row) / denom : 0.0;
    *g_col = d > 0.0 ? (mx / d - src.s.e_col) / denom : 0.0;
  }
  return (d - (src.s.e_row * my + src.s.e_col * mx)) / denom;
}

// The unknown of an accepted cell in the variables of `label`: tau with T = t0 + T0 tau, or
// T itself without a label.
double FireFront::unknown_of(int cell, int label) const {
  if (label < 0) return arrival_[cell];
  if (label_[cell] == label) return tau_[cell];
  const double t0f = factor(label, cell, nullptr, nullptr);
  const SourceRec& src = sources_[label];
  if (!(t0f > 1e-9 * std::min(dy_, dx_) / src.s.v)) return 1.0;
  return (arrival_[cell] - src.t0) / t0f;
}

const std::vector<int>& FireFront::advance(double t_end, const SpeedFn& speed) {
  if (std::isnan(t_end)) throw std::invalid_argument("t_end must not be NaN");
  accepted_now_.clear();
  while (!heap_.empty() && heap_.front().t <= t_end) {
    const Entry e = heap_.front();
    std::pop_heap(heap_.begin(), heap_.end(), Later());
    heap_.pop_back();
    if (state_[e.cell] == 2 || e.t != tent_[e.cell]) continue;  // stale entry
    if (!inside_[e.cell]) {  // masked out after it entered the band
      state_[e.cell] = 0;
      fixed_[e.cell] = 0;
      tent_[e.cell] = kInf;
      --n_trial_;
      continue;
    }
    accept(e.cell, e.t);
    if (cellular())
      relax_cellular(e.cell, speed);
    else
      update_fmm_neighbours(e.cell, speed);
  }
  t_done_ = std::max(t_done_, t_end);
  return accepted_now_;
}

// The paper's rule: the neighbour n of a burning cell c ignites at t(c) + |cn| / V, with the
// slowness averaged over the edge's two ends (trapezoid rule) and V the ellipse ray speed.
void FireFront::relax_cellular(int cell, const SpeedFn& speed) {
  const LocalSpeed sc = speed(cell);
  if (!(sc.v > 0.0)) return;
  const int r = cell / nx_, c = cell % nx_;
  const double tc = arrival_[cell];
  for (const Step& st : steps_) {
    const int nr = r + st.dr, nc = c + st.dc;
    if (nr < 0 || nr >= ny_ || nc < 0 || nc >= nx_) continue;
    const int n = nr * nx_ + nc;
    if (!inside_[n] || state_[n] == 2) continue;
    const LocalSpeed sn = speed(n);
    if (!(sn.v > 0.0)) continue;
    const double slowness = 0.5 * (1.0 / ray_speed(sc, st.ur, st.uc) + 1.0 / ray_speed(sn, st.ur, st.uc));
    const double t = tc + st.length * slowness;
    if (!(t < tent_[n])) continue;
    if (st.n_pass) {
      const int p0 = (r + st.pass_dr[0]) * nx_ + c + st.pass_dc[0];
      const int p1 = (r + st.pass_dr[1]) * nx_ + c + st.pass_dc[1];
      const bool open = st.need_both ? can_burn(p0, speed) && can_burn(p1, speed)
                                     : can_burn(p0, speed) || can_burn(p1, speed);
      if (!open) continue;
    }
    push(n, t, t, -1);
  }
}

void FireFront::update_fmm_neighbours(int cell, const SpeedFn& speed) {
  const int r = cell / nx_, c = cell % nx_;
  const double tc = arrival_[cell];
  const double hmin = std::min(dy_, dx_);
  for (int k = 0; k < 8; ++k) {
    const int nr = r + kRingDr[k], nc = c + kRingDc[k];
    if (nr < 0 || nr >= ny_ || nc < 0 || nc >= nx_) continue;
    const int n = nr * nx_ + nc;
    if (!inside_[n] || state_[n] == 2) continue;
    const LocalSpeed sn = speed(n);
    if (!(sn.v > 0.0)) continue;
    const bool huygens = opt_.huygens && (sn.e_row != 0.0 || sn.e_col != 0.0);
    if (k >= 4 && !huygens) continue;  // diagonal neighbours only enter the Huygens update
    Solution sol = huygens ? solve_huygens(n, sn, speed) : solve_eikonal(n, sn);
    if (!(sol.t < kInf)) continue;
    if (sol.t < tc) {  // causality, also when the speed law changed between calls
      sol.t = tc;
      sol.label = -1;
      sol.tau = tc;
    }
    if (fixed_[n]) {
      // An exactly initialised cell keeps its time unless another front gets there clearly
      // earlier (by more than half a cell's travel time): discretisation noise must not
      // replace the exact value.
      const double slack = 0.5 * hmin / (sn.v * (1.0 + std::sqrt(drive_sq(sn))));
      if (!(sol.t < tent_[n] - slack)) continue;
      fixed_[n] = 0;
    }
    if (sol.t != tent_[n]) push(n, sol.t, sol.tau, sol.label);
  }
}

// Upwind difference candidates of one axis in the unknown u of `label`: (u - a) * c
// approximates |du/dx_axis|, sigma its sign. Second order, (3u - 4u1 + u2) / 2h, where the
// second upwind cell is accepted and not later than the first.
int FireFront::axis_candidates(int r, int c, int axis, bool all, int label, bool second,
                               AxisCand* out) const {
  const double h = axis == 0 ? dy_ : dx_;
  const int lim = axis == 0 ? ny_ : nx_;
  const int pos = axis == 0 ? r : c;
  const int stride = axis == 0 ? nx_ : 1;
  const int cell = r * nx_ + c;
  int n_out = 0;
  for (int side = -1; side <= 1; side += 2) {
    if (pos + side < 0 || pos + side >= lim) continue;
    const int n1 = cell + side * stride;
    if (state_[n1] != 2) continue;
    const double t1 = arrival_[n1];
    if (!all && n_out == 1 && !(t1 < out[0].t1)) continue;  // isotropic: the earlier one
    const double u1 = unknown_of(n1, label);
    AxisCand k{u1, 1.0 / h, side < 0 ? 1.0 : -1.0, t1};
    if (second && pos + 2 * side >= 0 && pos + 2 * side < lim) {
      const int n2 = cell + 2 * side * stride;
      if (state_[n2] == 2 && arrival_[n2] <= t1) {
        k.a = (4.0 * u1 - unknown_of(n2, label)) / 3.0;
        k.c = 1.5 / h;
      }
    }
    out[all ? n_out : 0] = k;
    n_out = all ? n_out + 1 : 1;
  }
  return n_out;
}

// Label (source) of the earliest accepted neighbour among the first `ring` of the 8, or -1.
int FireFront::earliest_label(int r, int c, int ring) const {
  int label = -1;
  double tmin = kInf;
  for (int k = 0; k < ring; ++k) {
    const int nr = r + kRingDr[k], nc = c + kRingDc[k];
    if (nr < 0 || nr >= ny_ || nc < 0 || nc >= nx_) continue;
    const int n = nr * nx_ + nc;
    if (state_[n] == 2 && arrival_[n] < tmin) {
      tmin = arrival_[n];
      label = label_[n];
    }
  }
  return label;
}

// Whether T0 of `label` has a discrete minimum at the cell along each axis (T0 = its value).
void FireFront::factor_minimum(int label, int cell, double T0, bool out[2]) const {
  const int r = cell / nx_, c = cell % nx_;
  for (int axis = 0; axis < 2; ++axis) {
    out[axis] = true;
    const int lim = axis == 0 ? ny_ : nx_, pos = axis == 0 ? r : c, stride = axis == 0 ? nx_ : 1;
    for (int side = -1; side <= 1; side += 2)
      if (pos + side >= 0 && pos + side < lim && factor(label, cell + side * stride, nullptr, nullptr) < T0)
        out[axis] = false;
  }
}

// Solve h(grad T) = 1 at a cell, h(p) = v (e.p + sqrt((1-|e|^2)|p|^2 + (e.p)^2)), over the
// upwind neighbour combinations of the 4-neighbour stencil; two-sided solutions that are
// causal and upwind-consistent win, then one-sided ones. Fmm2 (factored) solves for tau in
// T = t0 + T0 tau (T0 the uniform-medium travel time from the source of the earliest
// neighbour), so grad T = tau grad T0 + T0 grad tau stays affine in the unknown.
FireFront::Solution FireFront::solve_eikonal(int cell, const LocalSpeed& s) const {
  const int r = cell / nx_, c = cell % nx_;
  int label = method_ == FrontMethod::Fmm2 && opt_.factored ? earliest_label(r, c, 4) : -1;
  double t0 = 0.0, T0 = 1.0, g[2] = {0.0, 0.0};
  if (label >= 0) {
    T0 = factor(label, cell, &g[0], &g[1]);
    t0 = sources_[label].t0;
    if (!(T0 > 1e-9 * std::min(dy_, dx_) / sources_[label].s.v)) {  // at the source point
      label = -1;
      t0 = 0.0, T0 = 1.0, g[0] = g[1] = 0.0;
    }
  }
  const bool iso = s.e_row == 0.0 && s.e_col == 0.0;
  AxisCand ax[2][2];
  int n_ax[2];
  const bool all = !iso;
  const bool second = method_ == FrontMethod::Fmm2;
  n_ax[0] = axis_candidates(r, c, 0, all, label, second, ax[0]);
  n_ax[1] = axis_candidates(r, c, 1, all, label, second, ax[1]);
  bool factor_min[2] = {false, false};
  if (label >= 0) factor_minimum(label, cell, T0, factor_min);
  // Two-sided solutions win over one-sided ones: a one-sided update drops a derivative (of
  // tau when factored) and can then undershoot. Inconsistent solutions are the last resort.
  Solution two{kInf, kInf, label}, one{kInf, kInf, label}, loose{kInf, kInf, label};
  for (int i = -1; i < n_ax[0]; ++i)
    for (int j = -1; j < n_ax[1]; ++j) {
      if (i < 0 && j < 0) continue;
      const AxisCand* use[2] = {i >= 0 ? &ax[0][i] : nullptr, j >= 0 ? &ax[1][j] : nullptr};
      // p(tau) = P tau + Q; causality: T >= every upwind neighbour used.
      double P[2], Q[2], tlo = -kInf;
      // Across a one-sided update (no upwind neighbour on that axis) T is at a discrete
      // minimum. If T0 has its minimum there too, the factor is trusted (dtau/dx = 0 across,
      // exact near a source); otherwise the factor's slope is wrong there and dT/dx = 0 is
      // taken, as unfactored marching does.
      for (int k = 0; k < 2; ++k) {
        P[k] = use[k] || !factor_min[k] ? 0.0 : g[k];
        Q[k] = 0.0;
        if (!use[k]) continue;
        P[k] = g[k] + T0 * use[k]->sigma * use[k]->c;
        Q[k] = -T0 * use[k]->sigma * use[k]->c * use[k]->a;
        tlo = std::max(tlo, use[k]->t1);
      }
      const double tau_lo = (tlo - t0) / T0;
      const double pl[2] = {P[0] * tau_lo + Q[0], P[1] * tau_lo + Q[1]};
      double dtau;
      if (!eikonal_root(P, pl, s, &dtau)) continue;
      bool ok = dtau >= 0.0;  // causal: not earlier than the neighbours used
      dtau = std::max(dtau, 0.0);
      const double tau = tau_lo + dtau;
      const double t = t0 + T0 * tau;
      // Upwind consistency: the characteristic must come from the side of every neighbour used.
      const double p[2] = {P[0] * dtau + pl[0], P[1] * dtau + pl[1]};
      double gh[2];
      characteristic(p, s, gh);
      const double tol = 1e-12 * (std::abs(gh[0]) + std::abs(gh[1]));
      for (int k = 0; k < 2; ++k)
        if (use[k] && use[k]->sigma * gh[k] < -tol) ok = false;
      Solution& slot = !ok ? loose : (use[0] && use[1]) ? two : one;
      if (t < slot.t) slot = Solution{t, label >= 0 ? tau : t, label};
    }
  return two.t < kInf ? two : one.t < kInf ? one : loose;
}

// Update of a cell with direction-dependent speed (Huygens / semi-Lagrangian): the front
// reaches x from a point y on the ring of its accepted 8 neighbours, T interpolated linearly
// along each ring edge (axis to diagonal neighbour), then travels straight to x at x's
// ellipse ray speed: T(x) = min_y T(y) + (|x - y| - e.(x - y)) / (v (1 - |e|^2)). The
// 4-neighbour Eulerian update is not used here: for the focus ellipse the characteristic
// often leaves the quadrant of the gradient's upwind neighbours, and that update then has no
// causal solution. Fmm2 interpolates tau (T = t0 + T0 tau) instead of T, which makes the
// update exact in a uniform medium.
FireFront::Solution FireFront::solve_huygens(int cell, const LocalSpeed& s,
                                             const SpeedFn& speed) const {
  // The ring in circular order: even k axis neighbours, odd k diagonals.
  static const int kCircDr[8] = {-1, -1, 0, 1, 1, 1, 0, -1}, kCircDc[8] = {0, 1, 1, 1, 0, -1, -1, -1};
  const int r = cell / nx_, c = cell % nx_;
  const double vw = s.v * (1.0 - drive_sq(s));
  double tv[8];
  bool ok[8];
  int nb[8];
  for (int k = 0; k < 8; ++k) {
    const int nr = r + kCircDr[k], nc = c + kCircDc[k];
    const bool inb = nr >= 0 && nr < ny_ && nc >= 0 && nc < nx_;
    nb[k] = inb ? nr * nx_ + nc : -1;
    ok[k] = inb && state_[nb[k]] == 2;
    tv[k] = ok[k] ? arrival_[nb[k]] : kInf;
  }
  int label = method_ == FrontMethod::Fmm2 && opt_.factored ? earliest_label(r, c, 8) : -1;
  double t0 = 0.0, T0x = 0.0;
  if (label >= 0) {
    T0x = factor(label, cell, nullptr, nullptr);
    t0 = sources_[label].t0;
    if (!(T0x > 1e-9 * std::min(dy_, dx_) / sources_[label].s.v)) label = -1;
  }
  auto travel = [&](double my, double mx) {  // from y to x, (my, mx) = x - y in metres
    return (std::hypot(my, mx) - (s.e_row * my + s.e_col * mx)) / vw;
  };
  double best = kInf;
  for (int k = 0; k < 8; ++k) {
    if (!ok[k]) continue;
    if ((k & 1) && !ok[k - 1] && !ok[(k + 1) & 7]) {  // no squeezing past two holes
      const bool pass = (nb[k - 1] >= 0 && can_burn(nb[k - 1], speed)) ||
                        (nb[(k + 1) & 7] >= 0 && can_burn(nb[(k + 1) & 7], speed));
      if (!pass) continue;
    }
    best = std::min(best, tv[k] + travel(-kCircDr[k] * dy_, -kCircDc[k] * dx_));
  }
  for (int k = 0; k < 8; ++k) {
    const int ka = (k & 1) ? (k + 1) & 7 : k;  // axis end of edge (k, k+1)
    const int kd = (k & 1) ? k : k + 1;        // diagonal end
    if (!ok[ka] || !ok[kd]) continue;
    // y = A + lambda q, x - y = d0 - lambda q with d0 = x - A perpendicular to q = D - A.
    const double d0r = -kCircDr[ka] * dy_, d0c = -kCircDc[ka] * dx_;
    const double qr = (kCircDr[kd] - kCircDr[ka]) * dy_, qc = (kCircDc[kd] - kCircDc[ka]) * dx_;
    const double a = std::hypot(d0r, d0c), b = std::hypot(qr, qc);
    const double eq = s.e_row * qr + s.e_col * qc;
    // Linear T: f'(lambda) = dT + (lambda b^2 / |x - y| + e.q) / vw = 0 in closed form.
    const double K = -(vw * (tv[kd] - tv[ka]) + eq);
    double lam = K <= 0.0 ? 0.0 : K >= b * b / std::hypot(a, b) ? 1.0 : K * a / (b * std::sqrt(b * b - K * K));
    if (label < 0) {
      if (lam > 0.0 && lam < 1.0)
        best = std::min(best, tv[ka] + lam * (tv[kd] - tv[ka]) + travel(d0r - lam * qr, d0c - lam * qc));
      continue;
    }
    best = std::min(best, huygens_factored(label, nb[ka], nb[kd], a, b, d0r, d0c, qr, qc, vw, s, lam));
  }
  if (label < 0) return Solution{best, best, -1};
  return Solution{best, (best - t0) / T0x, label};
}

// Minimise f(lambda) = t0 + T0(y) tau(lambda) + travel(y -> x) over the edge (tau linear) by
// safeguarded Newton from lam (the linear-T minimiser); kInf unless the minimum is interior.
double FireFront::huygens_factored(int label, int na, int nd, double a, double b, double d0r,
                                   double d0c, double qr, double qc, double vw,
                                   const LocalSpeed& s, double lam) const {
  const SourceRec& src = sources_[label];
  const double ua = unknown_of(na, label), dtau = unknown_of(nd, label) - ua;
  const double yr = (na / nx_ - src.row) * dy_, yc = (na % nx_ - src.col) * dx_;  // A - source
  const double vws = src.s.v * (1.0 - drive_sq(src.s));
  const double eq = s.e_row * qr + s.e_col * qc, esq = src.s.e_row * qr + src.s.e_col * qc;
  double lo = 0.0, hi = 1.0;
  lam = std::clamp(lam, 0.0, 1.0);
  for (int it = 0; it < 40; ++it) {
    const double pr = yr + lam * qr, pc = yc + lam * qc;  // y - source
    const double ny = std::hypot(pr, pc), dxy = std::hypot(a, lam * b);
    const double pq = ny > 0.0 ? (pr * qr + pc * qc) / ny : 0.0;
    const double T0 = (ny - (src.s.e_row * pr + src.s.e_col * pc)) / vws;
    const double T0p = (pq - esq) / vws;
    const double T0pp = ny > 0.0 ? (b * b - pq * pq) / ny / vws : 0.0;
    const double tau = ua + lam * dtau;
    const double fp = T0p * tau + T0 * dtau + (lam * b * b / dxy + eq) / vw;
    const double fpp = T0pp * tau + 2.0 * T0p * dtau + a * a * b * b / (dxy * dxy * dxy) / vw;
    if (fp > 0.0) hi = lam; else lo = lam;
    double next = fpp > 0.0 ? lam - fp / fpp : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - lam) < 1e-13 || hi - lo < 1e-13;
    lam = next;
    if (done) break;
  }
  if (!(lam > 0.0 && lam < 1.0)) return kInf;
  const double pr = yr + lam * qr, pc = yc + lam * qc;
  const double T0 = (std::hypot(pr, pc) - (src.s.e_row * pr + src.s.e_col * pc)) / vws;
  const double mr = d0r - lam * qr, mc = d0c - lam * qc;
  return src.t0 + T0 * (ua + lam * dtau) + (std::hypot(mr, mc) - (s.e_row * mr + s.e_col * mc)) / vw;
}

std::vector<double> arrival_times(int ny, int nx, const std::vector<double>& speed,
                                  const std::vector<double>& e_row,
                                  const std::vector<double>& e_col,
                                  const std::vector<FrontSource>& sources, double dy, double dx,
                                  FrontMethod method) {
  FireFront front(ny, nx, dy, dx, method);
  const std::size_t n = static_cast<std::size_t>(ny) * nx;
  if (speed.size() != n)
    throw std::invalid_argument("speed must have ny*nx = " + std::to_string(n) + " entries");
  if (e_row.size() != e_col.size() || (!e_row.empty() && e_row.size() != n))
    throw std::invalid_argument("drive (e_row, e_col) must both be empty or have ny*nx entries");
  std::vector<std::uint8_t> inside(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (!(std::isfinite(speed[i]) && speed[i] >= 0.0))
      throw std::invalid_argument("speed must be finite and >= 0");
    inside[i] = speed[i] > 0.0;
    if (!e_row.empty()) {
      const double e2 = e_row[i] * e_row[i] + e_col[i] * e_col[i];
      if (!(e2 < 1.0)) throw std::invalid_argument("drive must be finite with |e| < 1");
    }
  }
  front.set_inside(inside);
  const bool iso = e_row.empty();
  const SpeedFn fn = [&](int c) {
    return iso ? LocalSpeed{speed[c]} : LocalSpeed{speed[c], e_row[c], e_col[c]};
  };
  for (const FrontSource& s : sources) front.ignite(s, fn);
  front.advance(kInf, fn);
  return front.arrival();
}

}  // namespace thinburn
