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

// Radius (in cells) of the disc around a point source whose times are set exactly. The
// source is a singularity of T; a second-order scheme started from one cell stays first
// order, so Fmm2 starts from a disc (docs/fire_front.md has the measurements).
constexpr double kInitRadiusFmm1 = 1.0;
constexpr double kInitRadiusFmm2 = 3.0;

bool finite_positive(double x) { return std::isfinite(x) && x > 0.0; }

double drive_sq(const LocalSpeed& s) { return s.e_row * s.e_row + s.e_col * s.e_col; }

}  // namespace

double ray_speed(const LocalSpeed& s, double ur, double uc) {
  return s.v * (1.0 - drive_sq(s)) / (1.0 - (s.e_row * ur + s.e_col * uc));
}

double normal_speed(const LocalSpeed& s, double nr, double nc) {
  const double en = s.e_row * nr + s.e_col * nc;
  return s.v * (en + std::sqrt(1.0 - drive_sq(s) + en * en));
}

FireFront::FireFront(int ny, int nx, double dy, double dx, FrontMethod method)
    : ny_(ny), nx_(nx), dy_(dy), dx_(dx), method_(method), t_done_(-kInf) {
  if (ny < 1 || nx < 1) throw std::invalid_argument("ny, nx: the grid must be at least 1 x 1");
  if (static_cast<long long>(ny) * nx > INT_MAX) throw std::invalid_argument("ny, nx: grid too large");
  if (!finite_positive(dy)) throw std::invalid_argument("dy must be finite and > 0");
  if (!finite_positive(dx)) throw std::invalid_argument("dx must be finite and > 0");
  const std::size_t n = static_cast<std::size_t>(ny) * nx;
  inside_.assign(n, 1);
  state_.assign(n, 0);
  fixed_.assign(n, 0);
  tent_.assign(n, kInf);
  arrival_.assign(n, kInf);
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

bool FireFront::accepted(int cell) const {
  if (cell < 0 || static_cast<std::size_t>(cell) >= state_.size())
    throw std::invalid_argument("cell index out of range");
  return state_[cell] == 2;
}

void FireFront::push(int cell, double t) {
  tent_[cell] = t;
  if (state_[cell] == 0) {
    state_[cell] = 1;
    ++n_trial_;
  }
  heap_.push_back({t, cell});
  std::push_heap(heap_.begin(), heap_.end(), [](const Entry& a, const Entry& b) {
    return a.t > b.t || (a.t == b.t && a.cell > b.cell);
  });
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
    if (state_[cell] != 2 && s.t0 < tent_[cell]) push(cell, s.t0);
    return;
  }
  ignite_fmm(s, cell, src, speed);
}

// Exact times t0 + distance / ray speed on the cells of a disc around the source, reached
// from the source cell without crossing cells that cannot burn.
void FireFront::ignite_fmm(const FrontSource& s, int cell, const LocalSpeed& src,
                           const SpeedFn& speed) {
  const double radius = method_ == FrontMethod::Fmm1 ? kInitRadiusFmm1 : kInitRadiusFmm2;
  ++stamp_id_;
  flood_.clear();
  flood_.push_back(cell);
  stamp_[cell] = stamp_id_;
  static const int kDr[4] = {-1, 1, 0, 0}, kDc[4] = {0, 0, -1, 1};
  for (std::size_t i = 0; i < flood_.size(); ++i) {
    const int q = flood_[i], qr = q / nx_, qc = q % nx_;
    const double my = (qr - s.row) * dy_, mx = (qc - s.col) * dx_;
    const double d = std::hypot(my, mx);
    const double t = s.t0 + (d > 0.0 ? d / ray_speed(src, my / d, mx / d) : 0.0);
    if (state_[q] != 2 && t < tent_[q]) {
      push(q, t);
      fixed_[q] = 1;
    }
    for (int k = 0; k < 4; ++k) {
      const int nr = qr + kDr[k], nc = qc + kDc[k];
      if (nr < 0 || nr >= ny_ || nc < 0 || nc >= nx_) continue;
      const int n = nr * nx_ + nc;
      if (stamp_[n] == stamp_id_ || !inside_[n]) continue;
      if (std::hypot(nr - s.row, nc - s.col) > radius) continue;
      stamp_[n] = stamp_id_;
      if (speed(n).v > 0.0) flood_.push_back(n);
    }
  }
}

const std::vector<int>& FireFront::advance(double t_end, const SpeedFn& speed) {
  if (std::isnan(t_end)) throw std::invalid_argument("t_end must not be NaN");
  accepted_now_.clear();
  auto later = [](const Entry& a, const Entry& b) {
    return a.t > b.t || (a.t == b.t && a.cell > b.cell);
  };
  while (!heap_.empty() && heap_.front().t <= t_end) {
    const Entry e = heap_.front();
    std::pop_heap(heap_.begin(), heap_.end(), later);
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
    if (st.n_pass) {
      const bool in0 = inside_[(r + st.pass_dr[0]) * nx_ + c + st.pass_dc[0]];
      const bool in1 = inside_[(r + st.pass_dr[1]) * nx_ + c + st.pass_dc[1]];
      if (st.need_both ? !(in0 && in1) : !(in0 || in1)) continue;
    }
    const LocalSpeed sn = speed(n);
    if (!(sn.v > 0.0)) continue;
    const double slowness = 0.5 * (1.0 / ray_speed(sc, st.ur, st.uc) + 1.0 / ray_speed(sn, st.ur, st.uc));
    const double t = tc + st.length * slowness;
    if (t < tent_[n]) push(n, t);
  }
}

void FireFront::update_fmm_neighbours(int cell, const SpeedFn& speed) {
  static const int kDr[4] = {-1, 1, 0, 0}, kDc[4] = {0, 0, -1, 1};
  const int r = cell / nx_, c = cell % nx_;
  const double tc = arrival_[cell];
  const double hmin = std::min(dy_, dx_);
  for (int k = 0; k < 4; ++k) {
    const int nr = r + kDr[k], nc = c + kDc[k];
    if (nr < 0 || nr >= ny_ || nc < 0 || nc >= nx_) continue;
    const int n = nr * nx_ + nc;
    if (!inside_[n] || state_[n] == 2) continue;
    const LocalSpeed sn = speed(n);
    if (!(sn.v > 0.0)) continue;
    double t = solve_fmm(n, sn);
    if (!(t < kInf)) continue;
    t = std::max(t, tc);  // causality, also when the speed law changed between calls
    if (fixed_[n]) {
      // An exactly initialised cell keeps its time unless another front gets there clearly
      // earlier (by more than half a cell's travel time): discretisation noise must not
      // replace the exact value.
      const double slack = 0.5 * hmin / (sn.v * (1.0 + std::sqrt(drive_sq(sn))));
      if (!(t < tent_[n] - slack)) continue;
      fixed_[n] = 0;
    }
    if (t != tent_[n]) push(n, t);
  }
}

// Upwind difference candidates of one axis: (T - a) * c approximates |dT/dx_axis|, sigma its
// sign. Second order, (3T - 4T1 + T2) / 2h, where the second upwind cell is accepted and not
// later than the first.
int FireFront::axis_candidates(int r, int c, int axis, bool all, AxisCand* out) const {
  const double h = axis == 0 ? dy_ : dx_;
  const int lim = axis == 0 ? ny_ : nx_;
  const int pos = axis == 0 ? r : c;
  const int stride = axis == 0 ? nx_ : 1;
  const int cell = r * nx_ + c;
  int n_out = 0;
  double t1_best = kInf;
  for (int side = -1; side <= 1; side += 2) {
    if (pos + side < 0 || pos + side >= lim) continue;
    const int n1 = cell + side * stride;
    if (state_[n1] != 2) continue;
    const double t1 = arrival_[n1];
    AxisCand k{t1, 1.0 / h, side < 0 ? 1.0 : -1.0};
    if (method_ == FrontMethod::Fmm2 && pos + 2 * side >= 0 && pos + 2 * side < lim) {
      const int n2 = cell + 2 * side * stride;
      if (state_[n2] == 2 && arrival_[n2] <= t1) {
        k.a = (4.0 * t1 - arrival_[n2]) / 3.0;
        k.c = 1.5 / h;
      }
    }
    if (all) {
      out[n_out++] = k;
    } else if (t1 < t1_best) {  // isotropic: the earlier neighbour is the upwind one
      t1_best = t1;
      out[0] = k;
      n_out = 1;
    }
  }
  return n_out;
}

// Solve h(grad T) = 1 at a cell, h(p) = v (e.p + sqrt((1-|e|^2)|p|^2 + (e.p)^2)), over the
// upwind neighbour combinations; the earliest upwind-consistent solution wins.
double FireFront::solve_fmm(int cell, const LocalSpeed& s) const {
  const int r = cell / nx_, c = cell % nx_;
  const bool iso = s.e_row == 0.0 && s.e_col == 0.0;
  AxisCand kr[2], kc[2];
  const int n_r = axis_candidates(r, c, 0, !iso, kr);
  const int n_c = axis_candidates(r, c, 1, !iso, kc);
  double best = kInf;
  for (int i = 0; i < n_r; ++i)
    best = std::min(best, kr[i].a + 1.0 / (kr[i].c * normal_speed(s, kr[i].sigma, 0.0)));
  for (int j = 0; j < n_c; ++j)
    best = std::min(best, kc[j].a + 1.0 / (kc[j].c * normal_speed(s, 0.0, kc[j].sigma)));
  if (n_r == 0 || n_c == 0) return best;

  const double w = 1.0 - drive_sq(s), iv = 1.0 / s.v;
  for (int i = 0; i < n_r; ++i)
    for (int j = 0; j < n_c; ++j) {
      // p(tau) = P tau + Q with tau = T - max(a) >= 0. Squaring h(p) = 1 gives the
      // quadratic w|p|^2 + 2 iv e.p - iv^2 = 0; C < 0 <=> h(Q) < 1, and then it has exactly
      // one positive root, the two-sided solution with T > both upwind values.
      const double amax = std::max(kr[i].a, kc[j].a);
      const double pr = kr[i].sigma * kr[i].c, pc = kc[j].sigma * kc[j].c;
      const double qr = pr * (amax - kr[i].a), qc = pc * (amax - kc[j].a);
      const double C = w * (qr * qr + qc * qc) + 2.0 * iv * (s.e_row * qr + s.e_col * qc) - iv * iv;
      if (!(C < 0.0)) continue;
      const double A = w * (pr * pr + pc * pc);
      const double B = 2.0 * w * (pr * qr + pc * qc) + 2.0 * iv * (s.e_row * pr + s.e_col * pc);
      const double sq = std::sqrt(B * B - 4.0 * A * C);
      const double tau = B >= 0.0 ? 2.0 * C / (-B - sq) : (-B + sq) / (2.0 * A);
      if (!iso) {
        // The characteristic (grad_p h) must come from inside the upwind quadrant.
        const double gr0 = pr * tau + qr, gc0 = pc * tau + qc;
        const double ep = s.e_row * gr0 + s.e_col * gc0;
        const double S = std::sqrt(w * (gr0 * gr0 + gc0 * gc0) + ep * ep);
        const double gr = s.e_row + (w * gr0 + ep * s.e_row) / S;
        const double gc = s.e_col + (w * gc0 + ep * s.e_col) / S;
        if (kr[i].sigma * gr < -1e-12 || kc[j].sigma * gc < -1e-12) continue;
      }
      best = std::min(best, amax + tau);
    }
  return best;
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
