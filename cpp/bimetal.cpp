#include "bimetal.hpp"

#include <algorithm>
#include <cmath>

#include "dynamics.hpp"
#include "threads.hpp"

namespace thinburn {
namespace {

constexpr double kPi = 3.14159265358979323846;
// A couple whose D changes by this much across its spacing curls across the front only.
constexpr double kAnisotropicTurn = 0.25;
// A shell whose normal turns by less than this across a couple's spacing is nearly flat there:
// the curl's change of Gaussian curvature is taken out only in part (measure_shape), fading
// as the turn drops below it. Below kCurvedTurn * 1e-7 (rounding's share of a flat sheet's
// normals) nothing is taken out at all, so a flat sheet, however it lies, bends as it did.
constexpr double kCurvedTurn = 0.01;

double chord_ratio(double kappa, double sep) {
  // Chord over arc of a mid-surface bent to curvature kappa over arc length sep, as
  // Bimetal::ratio's with both offsets 0 (and its half-turn clamp).
  if (!(sep > 0.0)) return 1.0;
  const double half = 0.5 * std::clamp(kappa, -kPi / sep, kPi / sep) * sep;
  return std::abs(half) > 1e-12 ? std::sin(half) / half : 1.0;
}

}  // namespace

Bimetal::Bimetal(const View& view) : s_(view) {}

void Bimetal::build() {
  const RowMatX3& r = s_.rest;
  const LatticeTopology& topo = s_.topology;
  const int C = topo.couples;
  grad_dir_ = RowMatX3::Zero(C, 3);
  grad_share_ = Eigen::VectorXd::Zero(C);
  changed_.assign(C, 0);
  couple_spacing_ = Eigen::VectorXd::Zero(C);
  for (int c = 0; c < C; ++c) {
    double sum = 0.0;
    int k = 0;
    for (int q = topo.nbr_offset[c]; q < topo.nbr_offset[c + 1]; ++q, ++k)
      sum += (couple_centre(r, topo.nbr_index[q]) - couple_centre(r, c)).norm();
    couple_spacing_(c) = k > 0 ? sum / k : 1.0;
  }
  measure_shape();
  add_springs();
}

void Bimetal::measure_shape() {
  // A change dII of the shell's second fundamental form changes its Gaussian curvature by
  // tr(cof(S) dII) to first order, cof(S) = tr(S) P - S in the tangent plane (S the rest
  // shape operator). A thin shell, far stiffer in stretching than in bending, takes no such
  // change without stretching: the curl keeps only the part of itself that has none
  // (docs/dynamics.md §2, "Curved shells"). A flat sheet's cof(S) is zero: nothing changes there.
  const LatticeTopology& topo = s_.topology;
  const int C = topo.couples;
  const std::vector<Eigen::Matrix3d> S = shape_operators(s_.rest, topo);
  cofactor_.assign(C, Eigen::Matrix3d::Zero());
  cofactor_norm2_ = Eigen::VectorXd::Zero(C);
  for (int c = 0; c < C; ++c) {
    const Eigen::Vector3d n = (s_.rest.row(2 * c + 1) - s_.rest.row(2 * c)).normalized().transpose();
    const Eigen::Matrix3d cof = S[c].trace() * (Eigen::Matrix3d::Identity() - n * n.transpose()) - S[c];
    const double flat = kCurvedTurn / couple_spacing_(c);  // a curvature that counts as flat
    const double norm2 = cof.squaredNorm();
    if (!(norm2 > 1e-14 * flat * flat)) continue;
    cofactor_[c] = cof;
    cofactor_norm2_(c) = norm2 + flat * flat;
  }
}

double Bimetal::factor(int c, const Eigen::Vector3d& u) const {
  // How much of couple c's curl a spring along unit direction u takes: a share follows the
  // direction g in which D grows, the rest is alike every way; on a curved shell less the part
  // that would change the Gaussian curvature (measure_shape).
  const Eigen::Vector3d g = grad_dir_.row(c).transpose();
  const double share = grad_share_(c), along = u.dot(g);
  double f = share * along * along + (1.0 - share) * 0.5;
  if (cofactor_norm2_(c) > 0.0) {
    const Eigen::Matrix3d& K = cofactor_[c];
    const double lambda = (share * g.dot(K * g) + (1.0 - share) * 0.5 * K.trace()) / cofactor_norm2_(c);
    f -= lambda * u.dot(K * u);
  }
  return f;
}

void Bimetal::add_springs() {
  // Geometry of the rest lattice that the bimetal rest lengths bend: each spring joins two
  // couples whose centres are mid_sep_ apart, at offsets +-(half the couple's thickness) from the
  // mid-surface (+ toward the top). Of the springs from the first not yet measured to the last.
  const RowMatX3& r = s_.rest;
  auto offset = [&](int v) {
    const double half = 0.5 * (r.row(v | 1) - r.row(v & ~1)).norm();
    return (v & 1) ? half : -half;
  };
  for (std::size_t s = mid_sep_.size(); s < s_.sa.size(); ++s) {
    base_len_.push_back(s_.rest_len[s]);
    mid_sep_.push_back((couple_centre(r, s_.sb[s] / 2) - couple_centre(r, s_.sa[s] / 2)).norm());
    off_a_.push_back(offset(s_.sa[s]));
    off_b_.push_back(offset(s_.sb[s]));
  }
}

void Bimetal::restore(RowMatX3&& grad_dir, Eigen::VectorXd&& grad_share) {
  grad_dir_ = std::move(grad_dir);
  grad_share_ = std::move(grad_share);
}

double Bimetal::ratio(int s, double kappa) const {
  // Distance between two points of a sheet bent to curvature kappa (centre of curvature on the
  // top side), at mid-surface arc length s apart and offsets oa, ob along the normals:
  // d^2 = (oa - ob)^2 + (1 - kappa oa)(1 - kappa ob) chord^2, chord = 2 sin(kappa s / 2) / kappa.
  // The top face (o > 0) shortens by kappa o per unit length, the bottom lengthens: a bimetal
  // strip. Returned relative to the flat sheet, so that the rest lattice's own shape is kept.
  const double sep = mid_sep_[s], oa = off_a_[s], ob = off_b_[s];
  const double d0 = std::sqrt((oa - ob) * (oa - ob) + sep * sep);
  if (!(d0 > 0.0) || sep == 0.0) return 1.0;
  // At most a half turn between the couples, and the layers stay on their side of the centre.
  const double omax = std::max(std::abs(oa), std::abs(ob));
  double k = std::clamp(kappa, -kPi / sep, kPi / sep);
  if (omax > 0.0) k = std::clamp(k, -0.9 / omax, 0.9 / omax);
  const double half = 0.5 * k * sep;
  const double chord = std::abs(half) > 1e-12 ? sep * std::sin(half) / half : sep;
  const double d2 = (oa - ob) * (oa - ob) + (1.0 - k * oa) * (1.0 - k * ob) * chord * chord;
  return std::sqrt(std::max(d2, 0.0)) / d0;
}

void Bimetal::update_gradients(const Eigen::VectorXd& D, const Eigen::VectorXd& delta, bool all) {
  // The direction in which D grows at each couple near a change (changed_), and how sharply.
  const LatticeTopology& topo = s_.topology;
  for (int c = 0; c < topo.couples; ++c) {
    bool near = all || delta(c) != 0.0;
    for (int q = topo.nbr_offset[c]; q < topo.nbr_offset[c + 1] && !near; ++q) near = delta(topo.nbr_index[q]) != 0.0;
    changed_[c] = near;
    if (!near) continue;
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (int q = topo.nbr_offset[c]; q < topo.nbr_offset[c + 1]; ++q) {
      const int o = topo.nbr_index[q];
      const Eigen::Vector3d e = couple_centre(s_.rest, o) - couple_centre(s_.rest, c);
      const double l2 = e.squaredNorm();
      if (l2 > 0) g += (D(o) - D(c)) * e / l2;
    }
    const double k = topo.nbr_offset[c + 1] - topo.nbr_offset[c];
    const double slope = k > 0 ? 2.0 * g.norm() / k : 0.0;  // |grad D| (rad/m), averaged over axes
    grad_share_(c) = std::min(1.0, slope * couple_spacing_(c) / kAnisotropicTurn);
    grad_dir_.row(c) = g.norm() > 0 ? Eigen::RowVector3d(g.normalized().transpose()) : Eigen::RowVector3d::Zero();
  }
}

double Bimetal::curvature(const Eigen::VectorXd& D, int ca, int cb) const {
  // The curvature between two couples: their mean D over spacing, along the front.
  Eigen::Vector3d u = couple_centre(s_.rest, cb) - couple_centre(s_.rest, ca);
  u = u.norm() > 0 ? Eigen::Vector3d(u.normalized()) : u;
  const double f = s_.p.anisotropic_curl ? 0.5 * (factor(ca, u) + factor(cb, u)) : 1.0;
  return 0.5 * s_.p.crumple_gain * f * (D(ca) / couple_spacing_(ca) + D(cb) / couple_spacing_(cb));
}

void Bimetal::apply(const Eigen::VectorXd& D, const Eigen::VectorXd& delta, bool all, Membrane* membrane) {
  // Only springs near a couple whose D changed are recomputed.
  //
  // The curl bends across the fire's front, not equally every way: a heated face shrinking
  // alike in all directions wants a dome, which a sheet cannot take without stretching, so
  // paper rolls about lines along the burning edge instead. A spring along unit direction u
  // takes the curvature times (u . g)^2, g the direction in which D grows (a couple's D
  // gradient); where D is flat across a couple (|grad D| spacing << kAnisotropicTurn) the
  // factor blends to 1/2, the mean over directions.
  update_gradients(D, delta, all);
  const int ns = static_cast<int>(s_.sa.size());
  parallel_for(0, ns, kRowCost, [&](long s_l) {
    const int s = static_cast<int>(s_l);
    const int ca = s_.sa[s] / 2, cb = s_.sb[s] / 2;
    if (ca == cb) return;  // a couple's own thickness spring keeps its length
    if (!changed_[ca] && !changed_[cb]) return;
    s_.rest_len[s] = base_len_[s] * ratio(s, curvature(D, ca, cb));
  });
  if (!membrane) return;
  // A membrane spring lies on the mid-surface: bent, its ends are a chord of the arc apart.
  std::vector<double>& rest = membrane->rest();
  parallel_for(0, membrane->size(), kRowCost, [&](long e_) {
    const int e = static_cast<int>(e_);
    const int ca = membrane->couple_a(e), cb = membrane->couple_b(e);
    if (!changed_[ca] && !changed_[cb]) return;
    rest[e] = membrane->base()[e] * chord_ratio(curvature(D, ca, cb), membrane->base()[e]);
  });
}

}  // namespace thinburn
