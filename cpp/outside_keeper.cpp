#include "outside_keeper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace thinburn {

std::vector<double> outside_signs(const std::vector<int>& piece, const std::vector<std::uint8_t>& on_rim,
                                  const std::vector<Eigen::Vector3d>& position,
                                  const std::vector<Eigen::Vector3d>& normal, const std::vector<double>& weight) {
  const int n = static_cast<int>(piece.size());
  std::vector<double> out(n, 0.0);
  int pieces = 0;
  for (int p : piece) pieces = std::max(pieces, p + 1);
  std::vector<std::uint8_t> open(pieces, 0);
  std::vector<Eigen::Vector3d> centre(pieces, Eigen::Vector3d::Zero());
  std::vector<double> total(pieces, 0.0), volume(pieces, 0.0);
  for (int i = 0; i < n; ++i) {
    if (piece[i] < 0) continue;
    if (on_rim[i]) open[piece[i]] = 1;
    centre[piece[i]] += weight[i] * position[i];
    total[piece[i]] += weight[i];
  }
  for (int p = 0; p < pieces; ++p)
    if (total[p] > 0) centre[p] /= total[p];
  for (int i = 0; i < n; ++i)
    if (piece[i] >= 0) volume[piece[i]] += weight[i] * (position[i] - centre[piece[i]]).dot(normal[i]);
  for (int i = 0; i < n; ++i)
    if (piece[i] >= 0 && !open[piece[i]] && volume[piece[i]] != 0.0) out[i] = volume[piece[i]] > 0 ? 1.0 : -1.0;
  return out;
}

OutsideKeeper::OutsideKeeper(const std::vector<int>& piece, const std::vector<std::uint8_t>& on_rim,
                             const RowMatX3& rest, double spacing)
    : spacing_(spacing) {
  const int C = static_cast<int>(piece.size());
  std::vector<Eigen::Vector3d> mid(C), axis(C);
  for (int c = 0; c < C; ++c) {
    mid[c] = 0.5 * (rest.row(2 * c) + rest.row(2 * c + 1)).transpose();
    axis[c] = (rest.row(2 * c + 1) - rest.row(2 * c)).transpose();
  }
  // The couples stand for about equal areas.
  outside_ = outside_signs(piece, on_rim, mid, axis, std::vector<double>(C, 1.0));
  for (int c = 0; c < C; ++c)
    if (outside_[c] != 0.0) closed_.push_back(c);
}

int OutsideKeeper::apply(const RowMatX3& x, const Eigen::VectorXd& burnt, double skin, double dt,
                         ParticleSystem& particles) {
  const int n = particles.count();
  if (closed_.empty() || n == 0) return 0;
  mid_.resize(static_cast<Eigen::Index>(outside_.size()), 3);
  for (int c : closed_) mid_.row(c) = 0.5 * (x.row(2 * c) + x.row(2 * c + 1));
  grid_.build(closed_, mid_, spacing_);
  const auto P = particles.positions();
  const auto V = particles.velocities();
  int moved = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = P.row(i).transpose();
    Eigen::Array3i k0, k1;
    const Eigen::Vector3d lo = p.array() - spacing_, hi = p.array() + spacing_;
    if ((lo.array() > grid_.hi().array()).any() || (hi.array() < grid_.lo().array()).any()) continue;
    grid_.range(lo, hi, k0, k1);
    int best = -1;
    double best_d2 = spacing_ * spacing_;
    for (int a = k0(0); a <= k1(0); ++a)
      for (int b = k0(1); b <= k1(1); ++b)
        for (int e = k0(2); e <= k1(2); ++e)
          for (const int* it = grid_.begin(a, b, e), *end = grid_.end(a, b, e); it != end; ++it) {
            const double d2 = (mid_.row(*it).transpose() - p).squaredNorm();
            if (d2 < best_d2) best_d2 = d2, best = *it;
          }
    // A couple burnt through (half its sheet or more) is a hole: flames pass.
    if (best < 0 || burnt[best] >= 0.5) continue;
    const Eigen::Vector3d axis = (x.row(2 * best + 1) - x.row(2 * best)).transpose();
    if (!(axis.squaredNorm() > 0.0)) continue;
    const Eigen::Vector3d nrm = outside_[best] * axis.normalized();
    const double s = (p - mid_.row(best).transpose()).dot(nrm);
    if (s >= skin) continue;
    // Only a particle that came in over this step (it was outside, or on the skin, before):
    // one already inside (through a hole) stays inside.
    const double before = s - V.row(i).dot(nrm.transpose()) * dt;
    if (before < -skin) continue;
    particles.push_out(i, p + (skin - s) * nrm, nrm);
    ++moved;
  }
  return moved;
}

}  // namespace thinburn
