#include "contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dynamics.hpp"
#include "threads.hpp"

namespace thinburn {

Contacts::Contacts(int n, const View& view) : s_(view) {
  contact_ = Eigen::VectorXd::Constant(n, -1.0);
  stick_.assign(n, 0);
  slide_ = RowMatX3::Zero(n, 3);
  list_.reserve(n);
}

double Contacts::floor_at(int v) const {
  return floor_offset_.size() ? s_.p.floor_z + floor_offset_[v] : s_.p.floor_z;
}

void Contacts::set_colliders(std::shared_ptr<const Colliders> colliders, double margin, ContactSamples samples) {
  colliders_ = std::move(colliders);
  collider_margin_ = margin;
  collider_version_ = colliders_ ? colliders_->version() : 0;
  motion_.clear();
  shell_ = colliders_ && !samples.empty() ? std::make_unique<ShellContact>(std::move(samples)) : nullptr;
}

bool Contacts::colliders_moved(double dt) {
  if (!colliders_) return false;
  motion_.update(*colliders_, dt);
  if (colliders_->version() == collider_version_) return false;
  collider_version_ = colliders_->version();
  return true;
}

void Contacts::decide(int v, double h, const Eigen::Vector3d& f) {
  const RowMatX3& x = s_.lattice.positions();
  const RowMatX3& vel = s_.vel;
  const Eigen::VectorXd& mass = s_.mass;
  contact_(v) = -1.0;
  stick_[v] = 0;
  slide_.row(v).setZero();
  if (s_.p.has_floor && x(v, 2) <= floor_at(v)) {
    const double vz_free = vel(v, 2) + h * f.z() / mass(v);
    if (vz_free <= 0.0) {
      contact_(v) = -vz_free;
      // Static friction inside the solve: a contact whose tangential speed at the substep's
      // end (explicit guess) the floor's friction impulse (friction x the normal speed it
      // removes) can absorb sticks, all three velocity components filtered to zero. Applied
      // after the solve instead, friction stopped such a vertex only once its neighbours had
      // been solved as if it slid, and a sheet a light wind pushed crept across its table
      // by an amount proportional to the substep (the demo's A4 in 3 m/s wind: 0.39 m in
      // 20 s at dt = 1/24 s, against 7 mm with the symplectic integrator's small substeps).
      const double tx = vel(v, 0) + h * f.x() / mass(v), ty = vel(v, 1) + h * f.y() / mass(v);
      // A contact that Fig. 5's prescribed crumple moves this step follows it (the chord's
      // in-plane part is what lets its neighbours lift): it slides, as before.
      stick_[v] = s_.p.friction > 0.0 && s_.drift.row(v).squaredNorm() == 0.0 &&
                  std::hypot(tx, ty) <= s_.p.friction * contact_(v);
    }
  }
}

Eigen::Vector3d Contacts::substep_drift(int v, double h) const {
  Eigen::Vector3d u = s_.drift.row(v).transpose();
  // A floor contact ends the substep on the floor (B&W's position alteration y = h u), lifted
  // only by the crumple: this also lands a contact that starts above the floor.
  // Static friction also holds it in place against the crumple's sliding: the crumple lifts a
  // resting sheet off the table but does not drag it across. Without this, repeated crumples
  // with plastic rest lengths walk a sheet across the floor like an inchworm.
  if (s_.slot[v] >= 0 && contact_(v) >= 0.0) {
    u.z() = std::max(u.z(), 0.0) + (floor_at(v) - s_.lattice.positions()(v, 2)) / h;
    if (s_.p.friction > 0.0) u.x() = u.y() = 0.0;
  }
  return u;
}

bool Contacts::add_landings(double h, double* dv) {
  // The contact test before the solve sees only vertices already on the floor, with an explicit
  // guess of their velocity. A vertex a hair above the floor (lifted by a crumple, or by
  // rounding), or one the guess let go, is free in the solve, and a frame-sized substep then
  // carries it, and its whole couple, far below the floor (g dt^2 = 17 mm at 1/24 s); projecting
  // both layers back onto the floor flattened the couple. Such vertices become contacts and the
  // system is solved again. Of a couple only the vertex that ends lower lands first: its partner
  // is below the floor only because it fell with it, and the stiff top-bottom spring holds it
  // once the lower one is stopped (it lands in a later round if it still goes below).
  if (!s_.p.has_floor) return false;
  const RowMatX3& x = s_.lattice.positions();
  const RowMatX3& vel = s_.vel;
  auto end_z = [&](int v) {  // where the solution takes v this substep
    const int a = s_.slot[v];
    if (a < 0) return x(v, 2);
    return x(v, 2) + h * (vel(v, 2) + dv[3 * a + 2] + substep_drift(v, h).z());
  };
  list_.clear();
  for (int v : s_.active) {
    if (contact_(v) >= 0.0) continue;
    const double z = end_z(v);
    const int partner = v ^ 1;
    const bool partner_down = s_.slot[partner] >= 0 && contact_(partner) >= 0.0;
    if (z < floor_at(v) && (partner_down || z <= end_z(partner))) list_.push_back(v);
  }
  for (int v : list_) {  // after the loop: the test above reads contact_ of partners
    const int a = s_.slot[v];
    contact_(v) = std::max(0.0, -(vel(v, 2) + dv[3 * a + 2]));
    dv[3 * a + 2] = -vel(v, 2);
  }
  return !list_.empty();
}

bool Contacts::revise_contacts(double h, const std::function<Eigen::Vector3d(int slot)>& impulse) {
  // A contact is a prescribed v_z for the whole substep, so the floor could pull as well as
  // push: a vertex the rest of the shell lifts (a rolling shell's rear, a curling edge) was
  // held down, and a paper sphere rolling in a 3 m/s wind went 4.74 m in 4 s at 1/24 s against
  // 8.28 m under the symplectic integrator's projection, which never pulls; let go, 7.48 m.
  // A pull beyond a millionth of the vertex's weight over the substep (rounding) lets it go.
  //
  // A sticking contact's hold is decided before the solve, from an explicit guess; the solve
  // may then ask the floor for far more tangential impulse than friction gives (a sphere
  // rolling over a held vertex drags the whole shell back through it). Such a hold slides
  // instead, against friction times the floor's normal impulse, in the direction the hold
  // pushed, and the system is solved again. Held regardless, the rolling sphere after 2 s
  // went 3.11 m at dt = 1/96 s and 4.09 m at 1/24 s (symplectic: 3.98 m): how often a
  // contact lasted a substep decided how far it rolled; now 4.09 and 4.30 m.
  if (!s_.p.has_floor) return false;
  const double pull = 1e-6 * s_.p.gravity.norm() * h;  // per kg
  bool slid = false;
  list_.clear();
  for (int v : s_.active) {
    if (contact_(v) < 0.0) continue;
    const Eigen::Vector3d J = impulse(s_.slot[v]);
    const double jt = std::hypot(J.x(), J.y()), jn = std::max(J.z(), 0.0);
    if (J.z() < -pull * s_.mass(v)) {
      list_.push_back(v);
    } else if (stick_[v] && jt > s_.p.slip_ratio * s_.p.friction * jn + pull * s_.mass(v)) {
      // slip_ratio (3): let go only where the solve asks clearly more than friction allows. At 1
      // a mirror-symmetric burn's pair of corners, each at the threshold, let go one at a
      // time and the sheet slid 0.6 mm aside (tests/test_simulation_shell.py's symmetric
      // burn: 23 % of its motion against 0.64 %). The layers of a stack have no friction
      // between them (self_contact), so a top sheet held only where it droops onto the table
      // slid on the sheet below: the walkthrough's top letter 5.3 mm at 1.5, 2.6 mm at 3,
      // 0.3 mm at 10; the sphere's rolls spread 1.7 %, 6.7 % and 8.9 % over dt (docs/dynamics.md §3).
      stick_[v] = 0;
      slide_(v, 0) = s_.p.friction * jn * J.x() / jt;
      slide_(v, 1) = s_.p.friction * jn * J.y() / jt;
      slid = true;
    }
  }
  for (int v : list_) contact_(v) = -1.0, stick_[v] = 0, slide_.row(v).setZero();
  return slid || !list_.empty();
}

void Contacts::settle(int v, double h) {
  // A contact lands exactly on the floor (+ the crumple's lift), not a rounding below or
  // above it, so that the next substep's contact test finds it there.
  if (contact_(v) >= 0.0) s_.lattice.positions()(v, 2) = floor_at(v) + h * std::max(s_.drift(v, 2), 0.0);
}

void Contacts::press(int v) {
  // A vertex resting on the floor that the substep presses into it: the floor takes the
  // normal speed and friction the tangential one before the position moves. Applied after
  // the move (apply_floor alone), each substep let a resting vertex slide h^2 a_t first, and
  // a sheet that a light wind pushed crept across its table by T h a_t (the demo's A4 in
  // 3 m/s wind: 9 mm in 20 s at h = 1/6000 s).
  RowMatX3& vel = s_.vel;
  if (s_.p.has_floor && s_.lattice.positions()(v, 2) <= floor_at(v) && vel(v, 2) <= 0.0) {
    // The floor's tangent plane is x-y: hypot of the two in-plane components, not the 3-vector
    // norm of inelastic_coulomb (that rounds differently and would change every floor burn).
    const double keep = coulomb_keep(std::hypot(vel(v, 0), vel(v, 1)), s_.p.friction, -vel(v, 2));
    vel(v, 0) *= keep;
    vel(v, 1) *= keep;
    vel(v, 2) = 0.0;
  }
}

void Contacts::apply_floor(double h) {
  if (!s_.p.has_floor) return;
  RowMatX3& x = s_.lattice.positions();
  RowMatX3& vel = s_.vel;
  const bool implicit = is_implicit(s_.p.integrator);
  for (int v : s_.active) {
    // Coulomb friction: the tangential speed drops by friction times the normal speed the
    // floor removed (from the contact filter, or from the projection below); a hold let slide
    // had its friction in the solve (revise_contacts).
    const bool slid_in_solve = slide_.row(v).squaredNorm() > 0.0;
    double removed = -1.0;
    if (implicit && contact_(v) >= 0.0 && !slid_in_solve) removed = contact_(v);
    if (x(v, 2) < floor_at(v)) {
      removed = std::max(0.0, -vel(v, 2));
      x(v, 2) = floor_at(v);
      vel(v, 2) = std::max(0.0, vel(v, 2));
    }
    if (removed < 0.0) continue;
    const double keep = coulomb_keep(std::hypot(vel(v, 0), vel(v, 1)), s_.p.friction, removed);
    vel(v, 0) *= keep;
    vel(v, 1) *= keep;
  }
}

bool Contacts::collider_contact(const Eigen::Vector3d& x, ColliderHit& hit) const {
  // A vertex the last projection left at the margin is in contact: the slack covers the
  // rounding of that projection (a mesh's trilinear field is not exactly linear along n).
  constexpr double kSlack = 1e-7;  // m
  if (!colliders_) return false;
  hit = colliders_->query(x);
  return hit.distance < collider_margin_ + kSlack;
}

FloorSupport::FloorSupport(std::vector<int> start, std::vector<int> points, Eigen::VectorXd reach, Height height,
                           double half_thickness)
    : start_(std::move(start)), points_(std::move(points)), reach_(std::move(reach)), height_(std::move(height)),
      half_(half_thickness) {
  int n = 0;
  for (int p : points_) n = std::max(n, p + 1);
  z_.assign(n, 0.0);
  seen_.assign(n, 0);
}

double FloorSupport::point_height(const RowMatX3& x, int point) {
  // A point is carried by a few couples: take its height once per call.
  if (seen_[point] != call_) z_[point] = height_(x, point), seen_[point] = call_;
  return z_[point];
}

void FloorSupport::offsets(const RowMatX3& x, double floor_z, Eigen::VectorXd& out) {
  ++call_;
  const int C = static_cast<int>(reach_.size());
  // An offset moves only when the pose moved it by more than a hair: recomputed to rounding
  // each substep, a resting lantern's rim flickered in and out of contact (273 CG iterations a
  // frame against 13).
  const double hair = 1e-3 * half_;
  const bool fresh = out.size() != 2 * C;
  if (fresh) out.resize(2 * C);
  for (int c = 0; c < C; ++c) {
    // A couple without points (a flat sheet's: its mesh is the lattice's mid-surface) rests by
    // its centre: a couple of the rest thickness tilted to the unit direction n has its lower
    // vertex half a thickness times |n_z| below it, and both vertices are held there (the upper
    // one, carried by the thickness spring, touches only when the couple lies on its side). A
    // lying couple is held exactly as before (half a thickness); its current thickness is not
    // used: it oscillates under the explicit integrators, and a floor that moved with it
    // walked the symplectic A4 across its table (14.8 times its motion).
    if (start_[c + 1] == start_[c]) {
      const Eigen::Vector3d d = (x.row(2 * c + 1) - x.row(2 * c)).transpose();
      const double len = d.norm(), nz = len > 0.0 ? std::abs(d.z()) / len : 1.0;
      for (int v = 2 * c; v < 2 * c + 2; ++v) {
        const double offset = half_ * (1.0 - nz);
        if (fresh || std::abs(offset - out[v]) > hair) out[v] = offset;
      }
      continue;
    }
    // Out of reach of the floor (with thicknesses to spare): any offset that keeps it free.
    double low = 0.5 * (x(2 * c, 2) + x(2 * c + 1, 2)) - reach_[c];
    if (low <= floor_z + 4.0 * half_) {
      low = std::numeric_limits<double>::infinity();
      for (int k = start_[c]; k < start_[c + 1]; ++k) low = std::min(low, point_height(x, points_[k]));
    }
    for (int v = 2 * c; v < 2 * c + 2; ++v) {
      const double offset = x(v, 2) - low + half_;
      if (fresh || std::abs(offset - out[v]) > hair) out[v] = offset;
    }
  }
}

void Contacts::set_floor_support(std::unique_ptr<FloorSupport> support) {
  support_ = std::move(support);
  if (support_) support_->offsets(s_.lattice.positions(), s_.p.floor_z, floor_offset_);
}

void Contacts::begin_substep(double h) {
  if (support_) {
    // Where the substep heads (a sphere rolling a fifth of a turn a frame touches the floor with
    // the points it ends the substep on): the active vertices a substep of their velocity on.
    x_ahead_ = s_.lattice.positions();
    for (int v : s_.active) x_ahead_.row(v) += h * (s_.vel.row(v) + s_.drift.row(v));
    support_->offsets(x_ahead_, s_.p.floor_z, floor_offset_);
  }
  if (!colliders_) return;
  const RowMatX3& x = s_.lattice.positions();
  if (x_begin_.rows() != x.rows()) x_begin_ = x;
  for (int v : s_.active) x_begin_.row(v) = x.row(v);
  if (shell_) shell_->begin_substep(s_.slot);
}

int Contacts::apply_colliders(double h) {
  // Projection after the substep, as apply_floor does for the floor (docs/dynamics.md §3.2).
  // The substep's solve did not know the collider, so the vertex's couple partner moved with it
  // into the collider; the partner takes the same correction (the couple moves as one), or the
  // top layer would fall through a resting bottom layer by g h^2 every substep.
  if (!colliders_) return 0;
  constexpr int kProjections = 3;  // a mesh's field: a second try lands within ~1e-9 m
  RowMatX3& x = s_.lattice.positions();
  RowMatX3& vel = s_.vel;
  const std::vector<int>& active = s_.active;
  const int na = static_cast<int>(active.size());
  // Per active vertex, dx and dv of its contact (NaN in dx(0): none), computed in parallel.
  RowMatX3& dx = x_contact_;
  RowMatX3& dv = v_contact_;
  dx.resize(na, 3);
  dv.resize(na, 3);
  parallel_for(0, na, kRowCost, [&](long a) {
    const int v = active[a];
    dx(a, 0) = std::numeric_limits<double>::quiet_NaN();
    Eigen::Vector3d p = x.row(v).transpose();
    ColliderHit hit = colliders_->query(p);
    if (!(hit.distance < collider_margin_)) return;
    for (int k = 0; k < kProjections && hit.distance < collider_margin_; ++k) {
      p += (collider_margin_ - hit.distance) * hit.normal;
      hit = colliders_->query(p);
    }
    // Normal and friction act on the velocity relative to the collider: a moving box lifts and
    // carries what rests on it (a still one has exactly zero velocity).
    const Eigen::Vector3d vc = motion_.velocity(hit.index, p);
    const Eigen::Vector3d u = vel.row(v).transpose() - vc;
    const InelasticCoulomb c = inelastic_coulomb(u, hit.normal, hit.friction);
    // Friction acts within the substep, on the position: the vertex's move along the collider
    // since the substep's start (its own, the strain limit's) is held back by up to friction
    // times the depth pushed out, so one held by static friction does not creep down a slope
    // by h^2 g sin(angle) a substep.
    p = positional_friction(p, x_begin_.row(v).transpose() + h * vc, p - x.row(v).transpose(), hit);
    dx.row(a) = p.transpose() - x.row(v);
    dv.row(a) = (c.after() - u).transpose();
  });
  // Both vertices of a couple in contact: the deeper one's correction moves both (each its own
  // would squash the couple onto the margin).
  for (int a = 0; a < na; ++a) {
    if (std::isnan(dx(a, 0))) continue;
    const int v = active[a];
    const int b = s_.slot[v ^ 1];  // the couple's other vertex, -1 when it does not move
    if (b >= 0 && !std::isnan(dx(b, 0))) {
      const double mine = dx.row(a).squaredNorm(), theirs = dx.row(b).squaredNorm();
      if (mine < theirs || (mine == theirs && (v & 1))) continue;
    }
    x.row(v) += dx.row(a);
    vel.row(v) += dv.row(a);
    if (b >= 0) {
      x.row(v ^ 1) += dx.row(a);
      vel.row(v ^ 1) += dv.row(a);
    }
  }
  // Then the points of the shell between the control vertices, which a collider smaller than a
  // control cell passes between (a rod, a table's edge).
  return shell_ ? shell_->apply(*colliders_, motion_, collider_margin_, h, x_begin_, x, vel, s_.mass, s_.slot) : 0;
}

namespace {

// Substeps of a step dt that keep a contact's fall into a collider per substep, |g| h^2 + s h
// (s its inward speed), within travel (m): h is the positive root of that quadratic.
double contact_travel_substeps(double dt, double s, double g, double travel) {
  const double hmax = g > 0.0 ? (-s + std::sqrt(s * s + 4.0 * g * travel)) / (2.0 * g) : (s > 0.0 ? travel / s : dt);
  return std::ceil(dt / hmax);
}

}  // namespace

double Contacts::shortest_spring(int v) const {
  // Its shortest spring in the sheet's plane (not the couple's own), infinite when it has none.
  const SpringIncidence& inc = s_.incidence;
  double L = std::numeric_limits<double>::infinity();
  for (int q = inc.start[v]; q < inc.start[v + 1]; ++q)
    if (s_.kind[inc.spring[q]] != 3 && s_.rest_len[inc.spring[q]] > 0.0) L = std::min(L, s_.rest_len[inc.spring[q]]);
  return L;
}

int Contacts::contact_substeps(double dt) const {
  // A vertex that may reach a collider this step stops there while its spring neighbours, in the
  // solve, still move: per substep it may fall (s + |g| h) h into it, s its inward speed. That
  // must stay within kContactTravel of its shortest spring in the sheet's plane, so:
  // |g| h^2 + s h <= L. (max_stretch, 1 by default in a Simulation, lets contacts fall through
  // a couple's thickness: measured, a sheet on a 20 degree slope then slid at half of g sin.)
  constexpr double kContactTravel = 0.1;
  if (!colliders_) return 1;
  const RowMatX3& x = s_.lattice.positions();
  const double g = s_.p.gravity.norm();
  double need = 1.0;
  for (int v : s_.active) {
    const double speed = s_.vel.row(v).norm();
    const ColliderHit hit = colliders_->query(x.row(v).transpose());
    if (!(hit.distance < collider_margin_ + (speed + g * dt) * dt)) continue;
    const double L = shortest_spring(v);
    if (!std::isfinite(L)) continue;
    const double s = std::max(0.0, -s_.vel.row(v).dot(hit.normal));
    need = std::max(need, contact_travel_substeps(dt, s, g, kContactTravel * L));
  }
  if (shell_)
    need = std::max(need, shell_->substeps(*colliders_, collider_margin_, dt, g, x, s_.vel, s_.slot,
                                           [this](int v) { return shortest_spring(v); }));
  return static_cast<int>(std::min(need, double(s_.p.max_substeps)));
}

double Contacts::friction_reserve(int v, const Eigen::Vector3d& f) const {
  // What static friction could still take beyond f's tangential part: friction times the
  // inward push, less that part (negative once f slides the vertex; -inf off any support).
  const RowMatX3& x = s_.lattice.positions();
  double reserve = -std::numeric_limits<double>::infinity();
  if (s_.p.has_floor && x(v, 2) <= floor_at(v) && f.z() < 0.0)
    reserve = s_.p.friction * -f.z() - std::hypot(f.x(), f.y());
  ColliderHit hit;
  if (collider_contact(x.row(v).transpose(), hit)) {
    const double fn = f.dot(hit.normal);
    if (fn < 0.0) reserve = std::max(reserve, hit.friction * -fn - (f - fn * hit.normal).norm());
  }
  return reserve;
}

Eigen::Vector3d Contacts::supported(int v, Eigen::Vector3d f) const {
  const RowMatX3& x = s_.lattice.positions();
  if (s_.p.has_floor && x(v, 2) <= floor_at(v) && f.z() < 0.0) {
    const double normal = -f.z();
    f.z() = 0.0;
    const double keep = coulomb_keep(std::hypot(f.x(), f.y()), s_.p.friction, normal);
    f.x() *= keep;
    f.y() *= keep;
  }
  // A collider holds a vertex resting on it the same way: the inward push is taken, and static
  // friction takes up to friction times that of the tangential force.
  ColliderHit hit;
  if (collider_contact(x.row(v).transpose(), hit)) {
    const double fn = f.dot(hit.normal);
    if (fn < 0.0) {
      const Eigen::Vector3d ft = f - fn * hit.normal;
      f = coulomb_keep(ft.norm(), hit.friction, -fn) * ft;
    }
  }
  return f;
}

}  // namespace thinburn
