#include "heat.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "point_grid.hpp"
#include "threads.hpp"

namespace thinburn {
namespace {

using detail::KernelNode;

constexpr int kLeafSize = 32;
constexpr int kMaxDepth = 32;
constexpr int kStackSize = 8 * kMaxDepth + 16;  // depth-first: at most 7 siblings wait per level
constexpr double kLowerBoundTheta = 2.0;        // opening ratio of the lower-bound pass (measured)
constexpr double kPi = 3.14159265358979323846;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

template <int P>
inline double powi(double u) {
  return P == 1 ? u : u * u;
}

// K(d) = (d + d_min)^-P.
template <int P>
inline double kernel(double d, double d_min) {
  return powi<P>(1.0 / (d + d_min));
}

// The reference: every pair, sources in input order.
template <int P>
void direct_sum(const double* x, const double* w, int n, const RowMatX3& targets, double d_min,
                Eigen::VectorXd& out) {
  const Eigen::Index m = targets.rows();
  parallel_for(0, m, 8L * n, [&](long j) {
    const double yx = targets(j, 0), yy = targets(j, 1), yz = targets(j, 2);
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
      const double dx = yx - x[3 * i], dy = yy - x[3 * i + 1], dz = yz - x[3 * i + 2];
      s += w[i] * kernel<P>(std::sqrt(dx * dx + dy * dy + dz * dz), d_min);
    }
    out(j) = s;
  });
}

// The truncated kernel K(d) - K(cutoff) over the sources within the cutoff: sources in a
// dense grid of cells of the cutoff (a cell's sources in index order, so every target sums in
// a fixed order), each target visiting the cells its cutoff box meets.
template <int P>
void cutoff_sum(const RowMatX3& sources, const Eigen::VectorXd& w, const RowMatX3& targets, double d_min,
                double cutoff, Eigen::VectorXd& out) {
  thread_local PointGrid grid;
  thread_local std::vector<int> all;
  all.resize(static_cast<std::size_t>(sources.rows()));
  std::iota(all.begin(), all.end(), 0);
  grid.build(all, sources, cutoff);
  const double floor_value = kernel<P>(cutoff, d_min);
  out.setZero(targets.rows());
  if (all.empty()) return;
  const PointGrid& g = grid;
  parallel_for(0, targets.rows(), 64L, [&](long j) {
    const Eigen::Vector3d y = targets.row(j).transpose();
    const Eigen::Vector3d a = y.array() - cutoff, b = y.array() + cutoff;
    if ((a.array() > g.hi().array()).any() || (b.array() < g.lo().array()).any()) return;
    Eigen::Array3i k0, k1;
    g.range(a, b, k0, k1);
    double s = 0.0;
    for (int i = k0(0); i <= k1(0); ++i)
      for (int k = k0(1); k <= k1(1); ++k)
        for (int l = k0(2); l <= k1(2); ++l)
          for (const int* it = g.begin(i, k, l), *e = g.end(i, k, l); it != e; ++it) {
            const double d = (sources.row(*it).transpose() - y).norm();
            if (d < cutoff) s += w(*it) * (kernel<P>(d, d_min) - floor_value);
          }
    out(j) = s;
  });
}

void direct_sum(const double* x, const double* w, int n, const RowMatX3& targets, int p,
                double d_min, Eigen::VectorXd& out) {
  if (p == 1) {
    direct_sum<1>(x, w, n, targets, d_min, out);
  } else {
    direct_sum<2>(x, w, n, targets, d_min, out);
  }
}

// What a traversal needs of a built tree.
struct Tree {
  const KernelNode* nodes;
  const double* xs;
  const double* ws;
  double total_weight;
};

// Bound on |d^4/dt^4 K(|x + t e|)| over unit vectors e, for |x| >= r > 0, given
// v = 1 / (r + d_min) and ir = 1 / r. With s the cosine between x + t e and e and x = s^2,
// the derivative is a x^2 - b x (1 - x) + d (1 - x)(1 - 5 x) with a, b, d >= 0 decreasing in
// r (docs/heat.md); its positive part is <= max(a, d), its negative part <= b / 4 + 0.8 d.
template <int P>
inline double fourth_derivative_bound(double v, double ir) {
  const double g1 = P * powi<P>(v) * v, g2 = (P + 1) * g1 * v;
  const double g3 = (P + 2) * g2 * v, g4 = (P + 3) * g3 * v;
  const double a = g4, b = 6.0 * g3 * ir, d = 3.0 * ir * ir * (g2 + g1 * ir);
  return std::max(std::max(a, d), 0.25 * b + 0.8 * d);
}

struct Estimate {
  double lower, value, error;  // guaranteed lower bound, approximation, bound on its error
};

// The sum over a node is bracketed by [lower, upper] (every source lies at a distance in
// [dist - rho, dist + rho] and K decreases); inside that bracket, the Taylor expansion about
// the weighted centroid to third order (the first-order term vanishes) with a fourth-order
// remainder bound usually does much better. Returns error = +inf, cheaply, when the error
// bound cannot come within the budget rel * lower + abs.
template <int P>
Estimate estimate(const KernelNode& node, const Eigen::Vector3d& y, double d0, double rel,
                  double abs) {
  const Eigen::Vector3d r = node.centre - y;
  const double dist = r.norm(), rho = node.radius, w = node.weight;
  const double near = std::max(dist - rho, 0.0);
  const double v = 1.0 / (near + d0);
  Estimate est;
  est.lower = w * kernel<P>(dist + rho, d0);
  const double upper = w * powi<P>(v);
  est.value = 0.5 * (est.lower + upper);
  est.error = 0.5 * (upper - est.lower);
  if (!(near > 0.0)) return est;
  const double e4 =
      node.m4 > 0.0 ? fourth_derivative_bound<P>(v, 1.0 / near) * node.m4 * (1.0 / 24.0) : 0.0;
  if (!(std::min(e4, est.error) <= rel * est.lower + abs)) {
    est.error = INFINITY;
    return est;
  }
  // Taylor terms of orders 0, 2 and 3 about the centroid. K(|x - y|) has derivative tensors
  // g'' ee + g'/r (I - ee) and A eee + B sym(e I), with A = g''' - 3 B, B = g''/r - g'/r^2.
  const double u = 1.0 / (dist + d0), id = 1.0 / dist;
  const double g0 = powi<P>(u), g1 = -P * g0 * u, g2 = -(P + 1) * g1 * u, g3 = -(P + 2) * g2 * u;
  const double ex = r.x() * id, ey = r.y() * id, ez = r.z() * id;
  const double* q = node.q;
  const double* c = node.t;
  const double qee = ex * ex * q[0] + ey * ey * q[1] + ez * ez * q[2] +
                     2.0 * (ex * ey * q[3] + ex * ez * q[4] + ey * ez * q[5]);
  const double trq = q[0] + q[1] + q[2];
  const double teee = ex * ex * ex * c[0] + ey * ey * ey * c[1] + ez * ez * ez * c[2] +
                      3.0 * (ex * ex * (ey * c[3] + ez * c[4]) + ey * ey * (ex * c[5] + ez * c[6]) +
                             ez * ez * (ex * c[7] + ey * c[8])) +
                      6.0 * ex * ey * ez * c[9];
  const double tev =
      ex * (c[0] + c[5] + c[7]) + ey * (c[3] + c[1] + c[8]) + ez * (c[4] + c[6] + c[2]);
  const double bb = (g2 - g1 * id) * id, aa = g3 - 3.0 * bb;
  double t = w * g0 + 0.5 * (g2 * qee + g1 * id * (trq - qee)) +
             (aa * teee + 3.0 * bb * tev) * (1.0 / 6.0);
  t = std::min(std::max(t, est.lower), upper);
  const double et = std::min(e4, std::max(t - est.lower, upper - t));
  if (std::isfinite(t) && et <= est.error) {
    est.value = t;
    est.error = et;
  }
  return est;
}

template <int P>
double direct_leaf(const Tree& tree, const KernelNode& node, const Eigen::Vector3d& y,
                   double d0) {
  double s = 0.0;
  for (int i = node.begin; i < node.end; ++i) {
    const double* x = tree.xs + 3 * i;
    const double dx = y.x() - x[0], dy = y.y() - x[1], dz = y.z() - x[2];
    s += tree.ws[i] * kernel<P>(std::sqrt(dx * dx + dy * dy + dz * dz), d0);
  }
  return s;
}

// A guaranteed lower bound of the whole sum from a coarse cut of the tree.
template <int P>
double lower_bound(const Tree& tree, const Eigen::Vector3d& y, double d0) {
  int stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  double lb = 0.0;
  while (top > 0) {
    const KernelNode& node = tree.nodes[stack[--top]];
    const double dist = (y - node.centre).norm();
    if (node.child_count == 0 || node.radius <= kLowerBoundTheta * dist) {
      const Estimate est = estimate<P>(node, y, d0, 0.0, INFINITY);
      lb += std::max(est.lower, est.value - est.error);
    } else {
      for (int c = node.child_count - 1; c >= 0; --c) stack[top++] = node.first_child + c;
    }
  }
  return lb;
}

// One target's sum. A node is accepted when its error bound is within tol/2 of its own lower
// bound plus tol/2 of its weight's share of a lower bound of the whole sum: over all accepted
// nodes these budgets add up to at most tol times the sum. Otherwise it is opened; a leaf
// that cannot be accepted is summed directly.
template <int P>
void sum_target(const Tree& tree, const Eigen::Vector3d& y, double d0, double tol, double& value,
                double& bound) {
  const double half_tol = 0.5 * tol * (1.0 - 1e-12);
  const double per_weight = half_tol * lower_bound<P>(tree, y, d0) / tree.total_weight;
  int stack[kStackSize];
  int top = 0;
  stack[top++] = 0;
  value = 0.0;
  bound = 0.0;
  while (top > 0) {
    const KernelNode& node = tree.nodes[stack[--top]];
    const double abs = per_weight * node.weight;
    const Estimate est = estimate<P>(node, y, d0, half_tol, abs);
    if (est.error <= half_tol * est.lower + abs) {
      value += est.value;
      bound += est.error;
    } else if (node.child_count == 0) {
      value += direct_leaf<P>(tree, node, y, d0);
    } else {
      for (int c = node.child_count - 1; c >= 0; --c) stack[top++] = node.first_child + c;
    }
  }
}

template <int P>
void fast_sum(const Tree& tree, const RowMatX3& targets, double d0, double tol,
              Eigen::VectorXd& out, double* bound) {
  const Eigen::Index m = targets.rows();
  // A target's tree walk visits some tens of nodes of a few flops each.
  constexpr long kTargetCost = 256;
  parallel_for(0, m, kTargetCost, [&](long j) {
    double b = 0.0;
    sum_target<P>(tree, targets.row(j).transpose(), d0, tol, out(j), b);
    if (bound) bound[j] = b;
  });
}

void copy_points(const RowMatX3& m, std::vector<double>& out) {
  out.resize(std::size_t(m.rows()) * 3);
  std::copy(m.data(), m.data() + m.size(), out.begin());
}

void check_points(const RowMatX3& m, const char* name) {
  require(m.allFinite(), std::string(name) + " must be finite");
}

void check_sources(const RowMatX3& sources, const Eigen::VectorXd& w) {
  require(w.size() == sources.rows(), "weights must have one entry per source");
  check_points(sources, "sources");
  require(w.allFinite() && (w.size() == 0 || w.minCoeff() >= 0.0),
          "weights must be finite and >= 0");
  require(sources.rows() < (Eigen::Index(1) << 30), "sources: too many");
}

}  // namespace

void validate(const KernelSumOptions& opt) {
  require(opt.power == 1 || opt.power == 2, "power must be 1 or 2");
  require(std::isfinite(opt.d_min) && opt.d_min > 0.0, "d_min must be finite and > 0");
  require(opt.method == SumMethod::Direct || opt.method == SumMethod::Fast,
          "method must be Direct or Fast");
  require(std::isfinite(opt.tolerance) && opt.tolerance > 0.0 && opt.tolerance < 1.0,
          "tolerance must be in (0, 1)");
  require(std::isfinite(opt.cutoff) && opt.cutoff >= 0.0, "cutoff must be finite and >= 0");
}

void KernelSummer::build(const RowMatX3& sources, const Eigen::VectorXd& w) {
  check_sources(sources, w);
  copy_points(sources, raw_x_);
  raw_w_.assign(w.data(), w.data() + w.size());

  // Zero weights contribute nothing: the tree holds only the others.
  xs_.clear();
  ws_.clear();
  for (Eigen::Index i = 0; i < w.size(); ++i) {
    if (w(i) <= 0.0) continue;
    xs_.insert(xs_.end(), {sources(i, 0), sources(i, 1), sources(i, 2)});
    ws_.push_back(w(i));
  }
  const int n = int(ws_.size());
  nodes_.clear();
  total_weight_ = 0.0;
  if (n == 0) return;

  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d x(xs_[3 * i], xs_[3 * i + 1], xs_[3 * i + 2]);
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double half = std::max(0.5 * (hi - lo).maxCoeff(), 1e-300);
  order_.resize(n);
  scratch_.resize(n);
  octant_.resize(n);
  for (int i = 0; i < n; ++i) order_[i] = i;
  nodes_.emplace_back();
  nodes_[0].begin = 0;
  nodes_[0].end = n;
  split(0, 0.5 * (lo + hi), half, 0);

  // Apply the permutation so every node is a contiguous range, then take moments.
  std::vector<double>& px = raw_tmp_x_;
  std::vector<double>& pw = raw_tmp_w_;
  px.resize(xs_.size());
  pw.resize(ws_.size());
  for (int i = 0; i < n; ++i) {
    const int s = order_[i];
    for (int a = 0; a < 3; ++a) px[3 * i + a] = xs_[3 * s + a];
    pw[i] = ws_[s];
  }
  xs_.swap(px);
  ws_.swap(pw);
  for (detail::KernelNode& node : nodes_) moments(node);
  total_weight_ = nodes_[0].weight;
}

void KernelSummer::split(int idx, const Eigen::Vector3d& centre, double half, int depth) {
  const int begin = nodes_[idx].begin, end = nodes_[idx].end;
  if (end - begin <= kLeafSize || depth >= kMaxDepth) return;
  int counts[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int i = begin; i < end; ++i) {
    const double* x = &xs_[3 * order_[i]];
    const int o = (x[0] >= centre.x() ? 1 : 0) | (x[1] >= centre.y() ? 2 : 0) |
                  (x[2] >= centre.z() ? 4 : 0);
    octant_[i] = static_cast<unsigned char>(o);
    ++counts[o];
  }
  int start[8];
  int offset = begin, children = 0;
  for (int o = 0; o < 8; ++o) {
    start[o] = offset;
    offset += counts[o];
    children += counts[o] > 0 ? 1 : 0;
  }
  int fill[8];
  std::copy(start, start + 8, fill);
  for (int i = begin; i < end; ++i) scratch_[fill[octant_[i]]++] = order_[i];
  std::copy(scratch_.begin() + begin, scratch_.begin() + end, order_.begin() + begin);

  const int first = int(nodes_.size());
  nodes_[idx].first_child = first;
  nodes_[idx].child_count = children;
  for (int o = 0; o < 8; ++o) {
    if (counts[o] == 0) continue;
    detail::KernelNode child;
    child.begin = start[o];
    child.end = start[o] + counts[o];
    nodes_.push_back(child);
  }
  const double h = 0.5 * half;
  int c = first;
  for (int o = 0; o < 8; ++o) {
    if (counts[o] == 0) continue;
    const Eigen::Vector3d cc(centre.x() + ((o & 1) ? h : -h), centre.y() + ((o & 2) ? h : -h),
                             centre.z() + ((o & 4) ? h : -h));
    split(c++, cc, h, depth + 1);
  }
}

void KernelSummer::moments(detail::KernelNode& node) const {
  double w = 0.0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  for (int i = node.begin; i < node.end; ++i) {
    w += ws_[i];
    s += ws_[i] * Eigen::Vector3d(xs_[3 * i], xs_[3 * i + 1], xs_[3 * i + 2]);
  }
  node.weight = w;
  node.centre = s / w;
  double r2max = 0.0;
  std::fill(node.q, node.q + 6, 0.0);
  std::fill(node.t, node.t + 10, 0.0);
  node.m4 = 0.0;
  for (int i = node.begin; i < node.end; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(xs_[3 * i], xs_[3 * i + 1], xs_[3 * i + 2]) -
                              node.centre;
    const double r2 = d.squaredNorm(), wi = ws_[i];
    const double x = d.x(), y = d.y(), z = d.z();
    r2max = std::max(r2max, r2);
    const double q[6] = {x * x, y * y, z * z, x * y, x * z, y * z};
    for (int k = 0; k < 6; ++k) node.q[k] += wi * q[k];
    const double t[10] = {x * q[0], y * q[1], z * q[2], y * q[0], z * q[0],
                          x * q[1], z * q[1], x * q[2], y * q[2], x * q[5]};
    for (int k = 0; k < 10; ++k) node.t[k] += wi * t[k];
    node.m4 += wi * r2 * r2;
  }
  // The centroid is rounded, so pad the radius by a few ulps of the node's extent.
  node.radius = std::sqrt(r2max) * (1.0 + 1e-12) + 1e-15 * node.centre.cwiseAbs().maxCoeff();
}

void KernelSummer::evaluate(const RowMatX3& targets, const KernelSumOptions& opt,
                            Eigen::VectorXd& out, Eigen::VectorXd* error_bound) const {
  validate(opt);
  check_points(targets, "targets");
  const Eigen::Index m = targets.rows();
  out.setZero(m);
  if (error_bound) error_bound->setZero(m);
  if (opt.method == SumMethod::Direct) {
    direct_sum(raw_x_.data(), raw_w_.data(), int(raw_w_.size()), targets, opt.power, opt.d_min,
               out);
    return;
  }
  if (nodes_.empty()) return;
  const Tree tree{nodes_.data(), xs_.data(), ws_.data(), total_weight_};
  double* bound = error_bound ? error_bound->data() : nullptr;
  if (opt.power == 1) {
    fast_sum<1>(tree, targets, opt.d_min, opt.tolerance, out, bound);
  } else {
    fast_sum<2>(tree, targets, opt.d_min, opt.tolerance, out, bound);
  }
}

void kernel_sum(const RowMatX3& sources, const Eigen::VectorXd& w, const RowMatX3& targets,
                const KernelSumOptions& opt, Eigen::VectorXd& out, Eigen::VectorXd* error_bound) {
  validate(opt);
  if (opt.cutoff > 0.0) {
    check_sources(sources, w);
    check_points(targets, "targets");
    if (error_bound) error_bound->setZero(targets.rows());
    if (opt.power == 1) {
      cutoff_sum<1>(sources, w, targets, opt.d_min, opt.cutoff, out);
    } else {
      cutoff_sum<2>(sources, w, targets, opt.d_min, opt.cutoff, out);
    }
    return;
  }
  if (opt.method == SumMethod::Direct) {
    check_sources(sources, w);
    check_points(targets, "targets");
    out.setZero(targets.rows());
    if (error_bound) error_bound->setZero(targets.rows());
    direct_sum(sources.data(), w.data(), int(w.size()), targets, opt.power, opt.d_min, out);
    return;
  }
  thread_local KernelSummer summer;
  summer.build(sources, w);
  summer.evaluate(targets, opt, out, error_bound);
}

void particle_heat(const RowMatX3& particles, const Eigen::VectorXd& temperature,
                   const RowMatX3& vertices, double ct, double dt, const KernelSumOptions& opt,
                   Eigen::VectorXd& out, Eigen::VectorXd* error_bound) {
  require(opt.power == 2, "power must be 2 for particle heat (inverse-square law)");
  require(std::isfinite(ct) && ct >= 0.0, "ct must be finite and >= 0");
  require(std::isfinite(dt) && dt >= 0.0, "dt must be finite and >= 0");
  kernel_sum(particles, temperature, vertices, opt, out, error_bound);
  const double scale = ct * dt / (4.0 * kPi);
  out *= scale;
  if (error_bound) *error_bound *= scale;
}

void pyrolysis(const RowMatX3& ignition_points, const RowMatX3& vertices, double cp,
               const KernelSumOptions& opt, Eigen::VectorXd& out, Eigen::VectorXd* error_bound) {
  require(opt.power == 1, "power must be 1 for pyrolysis");
  require(std::isfinite(cp) && cp >= 0.0, "cp must be finite and >= 0");
  const Eigen::VectorXd ones = Eigen::VectorXd::Ones(ignition_points.rows());
  kernel_sum(ignition_points, ones, vertices, opt, out, error_bound);
  out *= cp;
  if (error_bound) *error_bound *= cp;
}

}  // namespace thinburn
