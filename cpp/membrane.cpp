#include "membrane.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "threads.hpp"

namespace thinburn {
namespace {

constexpr long kElemCost = 40;  // threads.hpp work units per membrane spring's block

std::uint64_t key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

std::unordered_map<std::uint64_t, int> spring_index(const std::vector<int>& sa, const std::vector<int>& sb) {
  std::unordered_map<std::uint64_t, int> idx;
  idx.reserve(2 * sa.size());
  for (std::size_t s = 0; s < sa.size(); ++s) idx.emplace(key(sa[s], sb[s]), static_cast<int>(s));
  return idx;
}

}  // namespace

Eigen::Matrix3d spring_block(const Eigen::Vector3d& d, double k, double rest, bool clamp) {
  const double l = d.norm();
  if (!(l > 1e-300)) return k * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d u = d / l;
  double g = 1.0 - rest / l;
  if (clamp) g = std::max(g, 0.0);
  const Eigen::Matrix3d uu = u * u.transpose();
  return k * (uu + g * (Eigen::Matrix3d::Identity() - uu));
}

Membrane::Membrane(const std::vector<int>& sa, const std::vector<int>& sb, const std::vector<std::uint8_t>& kind) {
  const auto idx = spring_index(sa, sb);
  carried_.assign(sa.size(), 0);
  for (std::size_t s = 0; s < sa.size(); ++s) {
    const int a = sa[s], b = sb[s];
    if (kind[s] > 2 || !(a & 1) || !(b & 1)) continue;  // a top-layer spring
    const auto twin = idx.find(key(a ^ 1, b ^ 1));
    if (twin == idx.end() || kind[twin->second] != kind[s]) continue;
    carried_[s] = carried_[twin->second] = 1;
    // Flex springs span two couples (or a hinge of two control triangles): a membrane spring
    // there would be a chord across a bent pair of cells, shorter than the arc by (2L)^3 k^2 / 24
    // even once the cells relax into a polygon, and so a bending stiffness of its own. The pair
    // keeps only its bending part; its membrane share goes to the structure springs' membrane
    // springs (LatticeDynamics::refresh_membrane).
    if (kind[s] == 2) continue;
    ca_.push_back(a / 2);
    cb_.push_back(b / 2);
    top_.push_back(static_cast<int>(s));
    bot_.push_back(twin->second);
  }
}

std::vector<std::pair<int, int>> Membrane::missing_diagonals(const std::vector<int>& sa,
                                                             const std::vector<int>& sb) const {
  auto idx = spring_index(sa, sb);
  std::vector<std::pair<int, int>> out;
  auto need = [&](int a, int b) {
    if (idx.emplace(key(a, b), -1).second) out.emplace_back(a, b);
  };
  for (int e = 0; e < size(); ++e) {
    need(2 * ca_[e] + 1, 2 * cb_[e]);
    need(2 * ca_[e], 2 * cb_[e] + 1);
  }
  return out;
}

void Membrane::link(const std::vector<int>& sa, const std::vector<int>& sb, const RowMatX3& rest, int couples) {
  const auto idx = spring_index(sa, sb);
  auto find = [&](int a, int b) {
    const auto it = idx.find(key(a, b));
    if (it == idx.end())
      throw std::invalid_argument("topology: membrane spring needs a spring between control vertices " +
                                  std::to_string(a) + " and " + std::to_string(b));
    return it->second;
  };
  const int ne = size();
  const int ns = static_cast<int>(sa.size());
  carried_.resize(ns, 0);
  blk_.resize(6 * std::size_t(ne));
  for (int e = 0; e < ne; ++e) {
    const int aT = 2 * ca_[e] + 1, aB = 2 * ca_[e], bT = 2 * cb_[e] + 1, bB = 2 * cb_[e];
    const int b6[6] = {top_[e], bot_[e], find(aT, bB), find(aB, bT), find(aB, aT), find(bB, bT)};
    std::copy(b6, b6 + 6, blk_.begin() + 6 * e);
  }
  // Per spring, the membrane springs writing to its block, with weights +-1/4 (membrane.hpp).
  share_start_.assign(ns + 1, 0);
  for (int b : blk_) ++share_start_[b + 1];
  for (int s = 0; s < ns; ++s) share_start_[s + 1] += share_start_[s];
  share_elem_.assign(blk_.size(), 0);
  share_w_.assign(blk_.size(), 0.0);
  std::vector<int> fill(share_start_.begin(), share_start_.end() - 1);
  for (int e = 0; e < ne; ++e)
    for (int j = 0; j < 6; ++j) {
      const int q = fill[blk_[6 * e + j]]++;
      share_elem_[q] = e;
      share_w_[q] = j < 4 ? 0.25 : -0.25;
    }
  couple_start_.assign(couples + 1, 0);
  for (int e = 0; e < ne; ++e) {
    ++couple_start_[ca_[e] + 1];
    ++couple_start_[cb_[e] + 1];
  }
  for (int c = 0; c < couples; ++c) couple_start_[c + 1] += couple_start_[c];
  couple_elem_.assign(2 * std::size_t(ne), 0);
  std::vector<int> cf(couple_start_.begin(), couple_start_.end() - 1);
  for (int e = 0; e < ne; ++e) {
    couple_elem_[cf[ca_[e]]++] = e;
    couple_elem_[cf[cb_[e]]++] = e;
  }
  base_.resize(ne);
  for (int e = 0; e < ne; ++e) base_[e] = (couple_centre(rest, cb_[e]) - couple_centre(rest, ca_[e])).norm();
  rest_ = base_;
  k_.assign(ne, 0.0);
  k_knee_.assign(ne, 0.0);
  jac_.assign(ne, Eigen::Matrix3d::Zero());
}

void Membrane::add_corners(int M) {
  corner_.clear();
  if (M < 2) return;
  std::unordered_map<std::uint64_t, int> pair;
  for (int e = 0; e < size(); ++e) pair.emplace(key(ca_[e], cb_[e]), e);
  auto spring = [&](int p, int q) {
    const auto it = pair.find(key(p, q));
    return it == pair.end() ? -1 : it->second;
  };
  for (const auto& [a, b, c] : grid_corners(M)) {
    Corner k{a, b, c, -1, -1, -1, 0.0};
    k.ab = spring(k.a, k.b), k.ac = spring(k.a, k.c), k.bc = spring(k.b, k.c);
    if (k.ab < 0 || k.ac < 0 || k.bc < 0) continue;  // not a grid's membrane
    // The rest diagonal from the pairs' rest lengths is not enough (it needs the angle): from
    // the membrane's base lengths by the parallelogram law, |b + c - 2a|^2 = 2|ab|^2 + 2|ac|^2 - |bc|^2.
    const double q = 2.0 * base_[k.ab] * base_[k.ab] + 2.0 * base_[k.ac] * base_[k.ac] - base_[k.bc] * base_[k.bc];
    if (!(q > 0.0)) continue;
    k.base = std::sqrt(q);
    corner_.push_back(k);
  }
}

Eigen::Vector3d Membrane::corner_diagonal(const Corner& k, const RowMatX3& x) const {
  return couple_centre(x, k.b) + couple_centre(x, k.c) - 2.0 * couple_centre(x, k.a);
}

double Membrane::corner_beyond(const Corner& k, double l, double* end) const {
  if (knee_ <= 0.0 || !(corner_k(k) > 0.0)) return 0.0;
  const double end_ = (1.0 + knee_) * k.base;
  if (l <= end_) return 0.0;
  if (end) *end = end_;
  return l - end_;
}

double Membrane::beyond_knee(int e, double l, double* end) const {
  if (knee_ <= 0.0 || !(k_knee_[e] > 0.0)) return 0.0;
  const double end_ = (1.0 + knee_) * base_[e];
  if (l <= end_) return 0.0;
  if (end) *end = end_;
  return l - end_;
}

Eigen::Vector3d Membrane::force(int v, const RowMatX3& x) const {
  const int c = v / 2;
  const Eigen::Vector3d me = couple_centre(x, c);
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  for (int q = couple_start_[c]; q < couple_start_[c + 1]; ++q) {
    const int e = couple_elem_[q];
    const Eigen::Vector3d d = couple_centre(x, ca_[e] == c ? cb_[e] : ca_[e]) - me;
    const double l = d.norm();
    if (l > 1e-300) f += 0.5 * (k_[e] * (l - rest_[e]) + k_knee_[e] * beyond_knee(e, l)) / l * d;
  }
  for (const Corner& k : corner_) {
    const int at[3] = {k.a, k.b, k.c};
    for (int i = 0; i < 3; ++i) {
      if (at[i] != c) continue;
      const Eigen::Vector3d g = corner_diagonal(k, x);
      const double l = g.norm(), over = corner_beyond(k, l);
      // E = k/2 over^2; dE/dc_i = coef_i k over g/l; a vertex carries half its centre's force.
      if (over > 0.0) f -= 0.5 * kCornerCoef[i] * corner_k(k) * over / l * g;
    }
  }
  return f;
}

double Membrane::energy(const RowMatX3& x) const {
  double w = 0.0;
  for (int e = 0; e < size(); ++e) {
    const double l = (couple_centre(x, cb_[e]) - couple_centre(x, ca_[e])).norm();
    const double dl = l - rest_[e], over = beyond_knee(e, l);
    w += 0.5 * k_[e] * dl * dl + 0.5 * k_knee_[e] * over * over;
  }
  for (const Corner& k : corner_) {
    const double over = corner_beyond(k, corner_diagonal(k, x).norm());
    w += 0.5 * corner_k(k) * over * over;
  }
  return w;
}

double Membrane::max_strain(const RowMatX3& x, const std::vector<int>& slot) const {
  double worst = 0.0;
  for (int e = 0; e < size(); ++e) {
    const int a = ca_[e], b = cb_[e];
    if (slot[2 * a] < 0 && slot[2 * a + 1] < 0 && slot[2 * b] < 0 && slot[2 * b + 1] < 0) continue;
    if (rest_[e] <= 0.0) continue;
    worst = std::max(worst, std::abs((couple_centre(x, b) - couple_centre(x, a)).norm() / rest_[e] - 1.0));
  }
  return worst;
}

void Membrane::blocks(const RowMatX3& x, const std::vector<int>& slot, bool clamp) {
  parallel_for(0, size(), kElemCost, [&](long e_) {
    const int e = static_cast<int>(e_);
    const int a = ca_[e], b = cb_[e];
    if (!slot.empty() && slot[2 * a] < 0 && slot[2 * a + 1] < 0 && slot[2 * b] < 0 && slot[2 * b + 1] < 0) return;
    const Eigen::Vector3d d = couple_centre(x, b) - couple_centre(x, a);
    jac_[e] = spring_block(d, k_[e], rest_[e], clamp);
    double end = 0.0;
    if (beyond_knee(e, d.norm(), &end) != 0.0) jac_[e] += spring_block(d, k_knee_[e], end, clamp);
  });
  for (const Corner& k : corner_) {
    // Hessian of k/2 over^2 in the centres: coef coef^T (x) H, H the spring block of g. As
    // pair blocks (+X on i-i and j-j, -X on i-j): X = 2H on a-b and a-c, -H on b-c.
    const auto fresh = [&](int e) {
      const int a = ca_[e], b = cb_[e];
      return slot.empty() || slot[2 * a] >= 0 || slot[2 * a + 1] >= 0 || slot[2 * b] >= 0 || slot[2 * b + 1] >= 0;
    };
    if (!fresh(k.ab) || !fresh(k.ac) || !fresh(k.bc)) continue;  // blocks left from an earlier call
    const Eigen::Vector3d g = corner_diagonal(k, x);
    double end = 0.0;
    if (corner_beyond(k, g.norm(), &end) == 0.0) continue;
    const Eigen::Matrix3d H = spring_block(g, corner_k(k), end, clamp);
    jac_[k.ab] += 2.0 * H;
    jac_[k.ac] += 2.0 * H;
    jac_[k.bc] -= H;
  }
}

Eigen::Matrix3d Membrane::share(int s) const {
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  for (int q = share_start_[s]; q < share_start_[s + 1]; ++q) J += share_w_[q] * jac_[share_elem_[q]];
  return J;
}

double Membrane::row_bound(int v, const RowMatX3& x, const Eigen::VectorXd& mass) const {
  // Row v of the membrane's part of K: J/4 on v itself, its partner and the other couple's two.
  const int c = v / 2;
  double b = 0.0;
  for (int q = couple_start_[c]; q < couple_start_[c + 1]; ++q) {
    const int e = couple_elem_[q];
    const int o = ca_[e] == c ? cb_[e] : ca_[e];
    const double l = (couple_centre(x, o) - couple_centre(x, c)).norm();
    const double g = l > 1e-300 ? std::abs(1.0 - rest_[e] / l) : 1.0;
    const double knee = beyond_knee(e, l) != 0.0 ? k_knee_[e] : 0.0;  // |1 - end / l| < 1 while l > end / 2
    const double w = 0.25 * (k_[e] + knee) * std::max(1.0, g) / std::sqrt(mass(v));
    b += w * (1.0 / std::sqrt(mass(v)) + 1.0 / std::sqrt(mass(v ^ 1)) + 1.0 / std::sqrt(mass(2 * o)) +
              1.0 / std::sqrt(mass(2 * o + 1)));
  }
  for (const Corner& k : corner_) {
    const int at[3] = {k.a, k.b, k.c};
    for (int i = 0; i < 3; ++i) {
      if (at[i] != c) continue;
      const Eigen::Vector3d g = corner_diagonal(k, x);
      double end = 0.0;
      if (corner_beyond(k, g.norm(), &end) == 0.0) continue;
      // Vertex blocks coef_i coef_j H / 4, |H| <= k max(1, |1 - end / l|).
      const double h = corner_k(k) * std::max(1.0, std::abs(1.0 - end / g.norm()));
      for (int j = 0; j < 3; ++j)
        b += 0.25 * std::abs(kCornerCoef[i] * kCornerCoef[j]) * h / std::sqrt(mass(v)) *
             (1.0 / std::sqrt(mass(2 * at[j])) + 1.0 / std::sqrt(mass(2 * at[j] + 1)));
    }
  }
  return b;
}

}  // namespace thinburn
