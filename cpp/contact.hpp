#pragma once
/// @brief The lattice's contacts with the floor and with collision objects (docs/dynamics.md
/// §3, §3.2): which vertices touch the floor in an implicit substep (the solve's filter), the
/// crumple's drift of a contact, the landings found after a solve, the projections after each
/// substep, the substeps contacts need, and the force a contact leaves a resting vertex.
#include <Eigen/Core>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "colliders.hpp"
#include "lattice.hpp"
#include "shell_contact.hpp"

namespace thinburn {

struct DynamicsParams;

/// @brief Coulomb friction's kept share of a contact's tangential speed t (m/s) when the contact
/// takes `removed` (m/s, >= 0) of normal speed: t drops by friction * removed, not below 0.
inline double coulomb_keep(double t, double friction, double removed) {
  return t > friction * removed ? (t - friction * removed) / t : 0.0;
}

/// @brief An inelastic contact with Coulomb friction on a velocity u relative to the support
/// (normal n, unit): its normal speed un, the inward part removed, the tangential velocity ut and
/// the share keep of it that friction leaves; after() is the velocity the contact leaves.
struct InelasticCoulomb {
  Eigen::Vector3d n;
  double un;
  double removed;
  Eigen::Vector3d ut;
  double keep;
  Eigen::Vector3d after() const { return std::max(un, 0.0) * n + keep * ut; }
};

inline InelasticCoulomb inelastic_coulomb(const Eigen::Vector3d& u, const Eigen::Vector3d& n, double friction) {
  InelasticCoulomb c;
  c.n = n;
  c.un = u.dot(n);
  c.removed = std::max(0.0, -c.un);
  c.ut = u - c.un * n;
  c.keep = coulomb_keep(c.ut.norm(), friction, c.removed);
  return c;
}

/// @brief Positional friction (as in position-based dynamics) for a point pushed out of a
/// collider: p, its position after the push, less its move along the collider since `from`
/// (where the collider's motion would have carried its start), up to the collider's friction
/// times the push (the change the push made, along hit.normal).
inline Eigen::Vector3d positional_friction(const Eigen::Vector3d& p, const Eigen::Vector3d& from,
                                           const Eigen::Vector3d& push, const ColliderHit& hit) {
  const Eigen::Vector3d& n = hit.normal;
  const Eigen::Vector3d moved = p - from;
  const Eigen::Vector3d slide = moved - moved.dot(n) * n;
  const double len = slide.norm(), hold = hit.friction * std::max(0.0, push.dot(n));
  return p - (len <= hold ? 1.0 : hold / len) * slide;
}

/// @brief A shell's floor (docs/lattice.md, "Floor"): per couple, the mesh points it carries
/// a fair share of (a curved shell's), or none (a flat sheet's, whose mesh is the lattice's
/// mid-surface: its couples rest by their centres, by their tilt). Which of them is lowest depends on how the shell
/// lies now, so offsets() places each control vertex above the floor by its height over the
/// lowest of its couple's points where they are now (couples within reach of the floor only),
/// plus the half thickness by which the dynamics' floor lies below the sheet's (a flat sheet's
/// bottom layer rests there).
class FloorSupport {
 public:
  /// @brief Height (m) of mesh point `point` for control positions x.
  using Height = std::function<double(const RowMatX3& x, int point)>;
  /// @brief points[start[c] .. start[c + 1]): the mesh points couple c carries (may be none:
  /// then it rests by its centre); reach[c]: the farthest of them from its mid-point at rest, m.
  FloorSupport(std::vector<int> start, std::vector<int> points, Eigen::VectorXd reach, Height height,
               double half_thickness);
  /// @brief Per control vertex of positions x (2 couples rows), its height above the floor
  /// floor_z (the dynamics') at which it touches it.
  void offsets(const RowMatX3& x, double floor_z, Eigen::VectorXd& out);

 private:
  double point_height(const RowMatX3& x, int point);

  std::vector<int> start_, points_;
  Eigen::VectorXd reach_;
  Height height_;
  double half_;
  std::vector<double> z_;            // scratch: heights taken in this call
  std::vector<std::uint32_t> seen_;  // the call that took z_[point]
  std::uint32_t call_ = 0;
};

class Contacts {
 public:
  /// @brief State of the lattice these contacts act on, kept by reference (the dynamics owns it).
  struct View {
    FfdLattice& lattice;               // positions
    RowMatX3& vel;                     // velocities, m/s
    const RowMatX3& drift;             // per vertex: the crumple's prescribed velocity this step
    const Eigen::VectorXd& mass;       // kg per vertex
    const std::vector<int>& active;    // the vertices integrated
    const std::vector<int>& slot;      // per vertex: its position in active, -1 if not in it
    const SpringIncidence& incidence;
    const std::vector<std::uint8_t>& kind;  // per spring (3: a couple's top-bottom spring)
    const std::vector<double>& rest_len;    // per spring, m
    const DynamicsParams& p;
  };
  Contacts(int n, const View& view);

  /// @brief A curved shell's floor: the offsets follow the shell's pose, taken afresh at every
  /// substep's start for the positions its velocities will reach by the substep's end.
  void set_floor_support(std::unique_ptr<FloorSupport> support);
  /// @brief The floor's height under vertex v, m.
  double floor_at(int v) const;
  /// @brief Collision objects (null: none), their margin (m, >= 0) and the shell's points that
  /// touch them besides the control vertices (empty: the control vertices only).
  void set_colliders(std::shared_ptr<const Colliders> colliders, double margin, ContactSamples samples = {});
  /// @brief A step of dt starts: the colliders' velocities over it (ColliderMotion); true once
  /// after each change of the colliders' version (a collider moved).
  bool colliders_moved(double dt);
  /// @brief What colliders_moved changes: the colliders' motion and the version seen. A step
  /// that is rolled back puts it back, so the step retried sees the same colliders' move.
  struct ColliderState {
    ColliderMotion motion;
    std::uint64_t version = 0;
  };
  ColliderState collider_state() const { return ColliderState{motion_, collider_version_}; }
  void restore(ColliderState&& s) {
    motion_ = std::move(s.motion);
    collider_version_ = s.version;
  }


  // The implicit solve's filter (Baraff and Witkin's S): a contact's v_z, and a sticking
  // contact's whole velocity, are prescribed; filter() zeroes those components of a 3-vector.
  bool in_contact(int v) const { return contact_(v) >= 0.0; }
  bool filtered(int v, int i) const { return contact_(v) >= 0.0 && (i == 2 || stick_[v]); }
  void filter(int v, double* x3) const {
    for (int i = 0; i < 3; ++i)
      if (filtered(v, i)) x3[i] = 0.0;
  }

  /// @brief Implicit substep h: decide whether active vertex v, under force f, is a floor
  /// contact and whether it sticks.
  void decide(int v, double h, const Eigen::Vector3d& f);
  /// @brief The velocity a vertex's position moves by this substep besides its own: the
  /// crumple's drift, and for a floor contact what lands it on the floor (and holds it there).
  Eigen::Vector3d substep_drift(int v, double h) const;
  /// @brief After an implicit solve (dv: 3 per active vertex, the velocity change): make the
  /// vertices it takes below the floor contacts, with dv's v_z prescribed; true if any.
  bool add_landings(double h, double* dv);
  /// @brief After a solve: contacts whose floor impulse (impulse(slot), kg m/s) pulls them down
  /// are let go, and sticking ones it holds beyond friction slide; returns whether any changed
  /// (then the system is solved again).
  bool revise_contacts(double h, const std::function<Eigen::Vector3d(int slot)>& impulse);
  /// @brief After an implicit substep's move: a contact sits exactly on the floor.
  void settle(int v, double h);
  /// @brief The friction impulse (kg m/s) the floor gives contact v in this substep's solve: a
  /// contact whose hold asked more than friction allows slides, against the floor's friction.
  Eigen::Vector3d friction_impulse(int v) const { return slide_.row(v).transpose(); }
  /// @brief Explicit substep, before the move: a vertex resting on the floor that the substep
  /// presses into it loses its normal speed and, by friction, its tangential speed.
  void press(int v);
  /// @brief After each substep: project the active vertices below the floor onto it, with
  /// Coulomb friction on what the floor removed.
  void apply_floor(double h);
  /// @brief A substep h starts: a curved shell's floor offsets for where it is heading, and the
  /// active vertices' positions for the colliders' positional friction.
  void begin_substep(double h);
  /// @brief After each substep: push the active vertices inside a collider's margin out, then
  /// the shell's samples; returns the samples pushed.
  int apply_colliders(double h);
  /// @brief Substeps of a step dt that the vertices nearing a collider need.
  int contact_substeps(double dt) const;
  /// @brief Force (N) that static friction could still take at vertex v, which force f
  /// presses on the floor or a collider, beyond f's own tangential part; < 0 when f slides it
  /// or it touches nothing.
  double friction_reserve(int v, const Eigen::Vector3d& f) const;
  /// @brief f less what a floor or a collider that vertex v rests on takes of it.
  Eigen::Vector3d supported(int v, Eigen::Vector3d f) const;

 private:
  bool collider_contact(const Eigen::Vector3d& x, ColliderHit& hit) const;
  double shortest_spring(int v) const;

  View s_;
  Eigen::VectorXd floor_offset_;  // per vertex, empty: none
  std::unique_ptr<FloorSupport> support_;  // a curved shell's floor (null: fixed offsets)
  RowMatX3 x_ahead_;                       // scratch: where the substep heads
  std::shared_ptr<const Colliders> colliders_;  // null: none
  double collider_margin_ = 0.0;
  std::uint64_t collider_version_ = 0;  // colliders_->version() when the sheet last woke for it
  ColliderMotion motion_;               // the colliders' velocities this step
  std::unique_ptr<ShellContact> shell_;  // the shell's sample points (null: none)
  RowMatX3 x_contact_, v_contact_;      // apply_colliders' per-active-vertex corrections
  RowMatX3 x_begin_;                    // per vertex: its position at the substep's start (colliders only)
  Eigen::VectorXd contact_;         // per vertex: floor impulse per mass of this substep, -1 if free
  std::vector<std::uint8_t> stick_; // per vertex: a contact held by static friction this substep
  RowMatX3 slide_;                  // per vertex: friction impulse of a contact let slide in the solve (kg m/s)
  std::vector<int> list_;           // scratch vertex list
};

}  // namespace thinburn
