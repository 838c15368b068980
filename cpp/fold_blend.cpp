#include "fold_blend.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "threads.hpp"

namespace thinburn {

namespace {

constexpr long kBlendCost = 24;  // one point's blend (4 couples' displacements), in threads.hpp units

Eigen::Vector3d centre(const RowMatX3& x, int c) { return 0.5 * (x.row(2 * c) + x.row(2 * c + 1)).transpose(); }

// The angle (degrees) between segments a and b; 0 where either has no length.
double turn_degrees(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double la = a.norm(), lb = b.norm();
  if (!(la > 0.0) || !(lb > 0.0)) return 0.0;
  return std::acos(std::clamp(a.dot(b) / (la * lb), -1.0, 1.0)) * (180.0 / 3.14159265358979323846);
}

double smoothstep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

}  // namespace

FoldBlend::FoldBlend(Embedding trilinear) : tri_(std::move(trilinear)) {
  if (tri_.stencil != 4) throw std::invalid_argument("FoldBlend needs a trilinear embedding (stencil 4)");
}

void FoldBlend::couple_weights(const FfdLattice& lattice) {
  const int M = lattice.M();
  const RowMatX3& x = lattice.positions();
  fold_.assign(std::size_t(M) * M, 0.0);
  weight_.assign(fold_.size(), 0.0);
  any_ = false;
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < M; ++j) {
      const int c = i * M + j;
      const Eigen::Vector3d p = centre(x, c);
      double turn = 0.0;
      if (i > 0 && i + 1 < M) turn = turn_degrees(p - centre(x, c - M), centre(x, c + M) - p);
      if (j > 0 && j + 1 < M) turn = std::max(turn, turn_degrees(p - centre(x, c - 1), centre(x, c + 1) - p));
      fold_[c] = smoothstep((turn - kFrom) / (kTo - kFrom));
      any_ = any_ || fold_[c] > 0.0;
    }
  if (!any_) return;
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < M; ++j) {
      double w = 0.0;
      for (int a = std::max(0, i - 1); a <= std::min(M - 1, i + 1); ++a)
        for (int b = std::max(0, j - 1); b <= std::min(M - 1, j + 1); ++b) w = std::max(w, fold_[a * M + b]);
      weight_[i * M + j] = w;
    }
}

void FoldBlend::set_keep_out(std::shared_ptr<const Colliders> colliders, double margin) {
  keep_out_ = std::move(colliders);
  keep_out_margin_ = margin;
}

void FoldBlend::apply(const FfdLattice& lattice, double z_min, Eigen::Ref<RowMatX3> out) {
  if (out.rows() != tri_.size()) throw std::invalid_argument("FoldBlend: out has the wrong number of rows");
  couple_weights(lattice);
  if (!any_) return;
  const RowMatX3& rest = lattice.rest();
  const int M = lattice.M();
  // Near a collider the spline's points stay: the blend fades in from keep_near to twice it
  // beyond the margin (a share of one couple spacing).
  const double keep_near = kKeepNear * std::max((centre(rest, 1) - centre(rest, 0)).norm(),
                                                (centre(rest, M) - centre(rest, 0)).norm());
  const RowMatX3& x = lattice.positions();
  // Each point writes its own row only: the same bits on any number of threads.
  parallel_for(0, static_cast<long>(tri_.size()), kBlendCost, [&](long p) {
    const std::int32_t* cp = tri_.couple.data() + 4 * p;
    const double* wt = tri_.weight.data() + 4 * p;
    double w = 0.0;
    for (int k = 0; k < 4; ++k) w += wt[k] * weight_[cp[k]];
    if (!(w > 0.0)) return;
    if (keep_out_) {
      const double d = keep_out_->query(out.row(p).transpose()).distance - keep_out_margin_;
      w *= smoothstep((d - keep_near) / keep_near);
      if (!(w > 0.0)) return;
    }
    // The trilinear point: rest plus the interpolated displacement, as FfdLattice::deform.
    const double r = tri_.r(p);
    Eigen::RowVector3d q = tri_.rest.row(p);
    for (int k = 0; k < 4; ++k) {
      const int bottom = 2 * cp[k], top = bottom + 1;
      q += wt[k] * ((1.0 - r) * (x.row(bottom) - rest.row(bottom)) + r * (x.row(top) - rest.row(top)));
    }
    out.row(p) += w * (q - out.row(p));
    out(p, 2) = std::max(out(p, 2), z_min);
  });
}

}  // namespace thinburn
