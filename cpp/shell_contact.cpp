#include "shell_contact.hpp"

#include "contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace thinburn {
namespace {

// A group is skipped when the collider's distance at the centre of its vertices' box exceeds
// the margin by this many half-diagonals. Exact distances change by at most 1 per metre; a mesh
// field read outside its grid (distance to the grid's box plus the border's value) over-reads by
// up to sqrt(2) of that (the border point is a projection onto a convex box), hence 1.5.
constexpr double kLipschitz = 1.5;

}  // namespace

ShellContact::ShellContact(ContactSamples samples) : s_(std::move(samples)) { share_.resize(s_.stencil); }

bool ShellContact::group_may_touch(int g, const Colliders& colliders, double margin, const RowMatX3& x,
                                   const std::vector<int>& slot) const {
  // A sample lies in the convex hull of its vertices (weights >= 0, summing to 1): if the
  // collider is farther than the margin from the whole box of the group's vertices, no sample
  // of the group touches it. With negative weights, p - c = sum w_k (x_k - c) is within
  // sum |w_k| (the spread) half-diagonals of the box's centre c. Groups all of whose vertices
  // sleep or are pinned cannot move; unused slots (weight 0) do not count.
  const std::size_t at = std::size_t(s_.group[g]) * s_.stencil;
  const int* v = s_.vertex.data() + at;
  const double* w = s_.weight.data() + at;
  bool awake = false;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (int k = 0; k < s_.stencil; ++k) {
    if (w[k] == 0.0) continue;
    awake |= slot[v[k]] >= 0;
    lo = lo.cwiseMin(x.row(v[k]).transpose());
    hi = hi.cwiseMax(x.row(v[k]).transpose());
  }
  if (!awake) return false;
  const ColliderHit hit = colliders.query(0.5 * (lo + hi));
  return hit.distance < margin + kLipschitz * s_.spread * 0.5 * (hi - lo).norm();
}

bool ShellContact::push_out(int s, const Colliders& colliders, const ColliderMotion& motion, double margin,
                            double h, const RowMatX3& x_begin, RowMatX3& x, RowMatX3& vel,
                            const Eigen::VectorXd& mass, const std::vector<int>& slot) {
  const int K = s_.stencil;
  const int* v = s_.vertex.data() + std::size_t(s) * K;
  const double* w = s_.weight.data() + std::size_t(s) * K;
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), p0 = Eigen::Vector3d::Zero(), u = Eigen::Vector3d::Zero();
  for (int k = 0; k < K; ++k) {
    p += w[k] * x.row(v[k]).transpose();
    p0 += w[k] * x_begin.row(v[k]).transpose();
    u += w[k] * vel.row(v[k]).transpose();
  }
  const ColliderHit hit = colliders.query(p);
  if (!(hit.distance < margin)) return false;
  // The least change of the vertices, in the mass metric sum m_k |dx_k|^2, that moves the sample
  // p = sum w_k x_k by dp: dx_k = w_k m_k^-1 dp / sum_j w_j^2 m_j^-1 (a Lagrange multiplier on
  // sum w_k dx_k = dp). The same for the velocity is an impulse J = dp / sum w_j^2 m_j^-1 at the
  // sample, shared out as w_k J (momentum changes by J exactly: the weights sum to 1).
  double W = 0.0;
  for (int k = 0; k < K; ++k) {
    share_[k] = slot[v[k]] >= 0 ? w[k] / mass(v[k]) : 0.0;  // sleeping and pinned vertices do not move
    W += w[k] * share_[k];
  }
  if (!(W > 0.0)) return false;
  // Inelastic and Coulomb, as a control vertex's contact (Contacts::apply_colliders), on the
  // sample's velocity relative to the collider.
  const Eigen::Vector3d vc = motion.velocity(hit.index, p);
  u -= vc;
  const InelasticCoulomb c = inelastic_coulomb(u, hit.normal, hit.friction);
  // Positional friction (as in position-based dynamics): the sample's tangential move over the
  // substep relative to the collider is held back by up to friction times the depth the push
  // removes. The move is measured from the substep's start, not taken from the velocity (h u_t,
  // as a control vertex's contact does): it also holds what the pushes of the samples next to
  // it, each along its own normal, did to it. On a curved collider those normals differ, and
  // each push slid its neighbours a little along the surface with no speed to stop: cloth
  // draped on a sphere crept off it at 2-6 mm/s (docs/dynamics.md §3.2).
  const double depth = margin - hit.distance;
  const Eigen::Vector3d out = depth * c.n;
  const Eigen::Vector3d dp = positional_friction(p + out, p0 + h * vc, out, hit) - p;
  const Eigen::Vector3d du = c.after() - u;
  for (int k = 0; k < K; ++k) {
    if (share_[k] == 0.0) continue;
    const double f = share_[k] / W;
    x.row(v[k]) += f * dp.transpose();
    vel.row(v[k]) += f * du.transpose();
    hold(v[k], f * depth * c.n);
  }
  return true;
}

void ShellContact::hold(int v, const Eigen::Vector3d& push) {
  if (!listed_[v]) {
    listed_[v] = 1;
    support_list_.push_back(v);
    support_.row(v).setZero();
  }
  support_.row(v) += push.transpose();
}

double ShellContact::substeps(const Colliders& colliders, double margin, double dt, double g, const RowMatX3& x,
                              const RowMatX3& vel, const std::vector<int>& slot,
                              const std::function<double(int)>& shortest) const {
  // Under gravity alone a sample at rest falls |g| h^2 a substep: where samples hold a stencil,
  // that is kept within kSampleTravel of the stencil's shortest spring. Without it a cloth
  // hanging on a 1 cm rod took 1 substep a step, squashed its springs by 28 % and was redone
  // with 29 (the next step with 2: 36 %, redone with 72): every step paid twice, and the sheet
  // jittered at 1-2 mm/s (median vertex) for good. The bound is not the redo's 1 %: measured on
  // that rod after 4-6 s (median / largest vertex speed), 0.5 % took 8 substeps and the sheet
  // swung along the rod at 10-17 / 40 mm/s; 0.2 %: 12, 0.8-1.0 / 20 mm/s; 0.05 %: 23, 1.2 / 4
  // mm/s (docs/dynamics.md §3.2). Only held stencils get it: counted whenever near, cloth on a
  // 1 m sphere, which its control vertices carry, took 24 substeps and crept at 0.6 mm/s.
  // A stencil moving into a collider, held or about to be, keeps its travel s h within the
  // control vertices' bound (kContactTravel in contact.cpp), so a landing's first step does not
  // take what the rest of the sheet needs.
  constexpr double kSampleTravel = 5e-4, kImpactTravel = 0.1;
  double need = 1.0;
  const bool any_held = !support_list_.empty();  // listed_ is unsized before the first apply
  const int groups = static_cast<int>(s_.group.size()) - 1;
  for (int gi = 0; gi < groups; ++gi) {
    const std::size_t at = std::size_t(s_.group[gi]) * s_.stencil;
    const int* v = s_.vertex.data() + at;
    const double* w = s_.weight.data() + at;
    bool awake = false, held = false;
    double L = std::numeric_limits<double>::infinity(), speed = 0.0, inward = 0.0;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (int k = 0; k < s_.stencil; ++k) {
      if (w[k] == 0.0) continue;
      lo = lo.cwiseMin(x.row(v[k]).transpose());
      hi = hi.cwiseMax(x.row(v[k]).transpose());
      if (slot[v[k]] < 0) continue;
      awake = true;
      L = std::min(L, shortest(v[k]));
      speed = std::max(speed, vel.row(v[k]).norm());
      if (any_held && listed_[v[k]]) {
        held = true;
        inward = std::max(inward, -vel.row(v[k]).dot(support_.row(v[k]).normalized()));
      }
    }
    if (!awake || !std::isfinite(L)) continue;
    if (held && g > 0.0) need = std::max(need, std::ceil(dt / std::sqrt(kSampleTravel * L / g)));
    if (!held && speed > 0.0) {
      const ColliderHit hit = colliders.query(0.5 * (lo + hi));
      if (!(hit.distance < margin + kLipschitz * s_.spread * 0.5 * (hi - lo).norm() + speed * dt)) continue;
      for (int k = 0; k < s_.stencil; ++k)
        if (w[k] != 0.0 && slot[v[k]] >= 0) inward = std::max(inward, -vel.row(v[k]).dot(hit.normal));
    }
    need = std::max(need, std::ceil(dt * inward / (kImpactTravel * L)));
  }
  return need;
}

void ShellContact::begin_substep(const std::vector<int>& slot) {
  std::size_t kept = 0;
  for (int v : support_list_)
    if (slot[v] >= 0)
      listed_[v] = 0;
    else
      support_list_[kept++] = v;
  support_list_.resize(kept);
}

int ShellContact::apply(const Colliders& colliders, const ColliderMotion& motion, double margin, double h,
                        const RowMatX3& x_begin, RowMatX3& x, RowMatX3& vel, const Eigen::VectorXd& mass,
                        const std::vector<int>& slot) {
  // Serial, in sample order (Gauss-Seidel): samples share vertices, and each one's correction
  // sees its neighbours' (Jacobi, each sample's own correction summed, would move a cell lying
  // on a face by about as many depths as it has samples in contact).
  if (support_.rows() != x.rows()) {
    support_ = RowMatX3::Zero(x.rows(), 3);
    listed_.assign(x.rows(), 0);
    support_list_.clear();
  }
  int moved = 0;
  const int groups = static_cast<int>(s_.group.size()) - 1;
  for (int back = 0; back < 2; ++back)
    for (int i = 0; i < groups; ++i) {
      const int g = back ? groups - 1 - i : i;
      if (!group_may_touch(g, colliders, margin, x, slot)) continue;
      const int first = s_.group[g], last = s_.group[g + 1] - 1;
      for (int s = first; s <= last; ++s)
        moved += push_out(back ? first + last - s : s, colliders, motion, margin, h, x_begin, x, vel, mass, slot);
    }
  return moved;
}

}  // namespace thinburn
