#pragma once
/// @brief Contact of the embedded shell with the colliders (docs/dynamics.md §3.2): points of the
/// sheet between the control vertices, each carried by a fixed set of them, that a collider
/// smaller than a control cell (a rod, a table's edge, a small ball) would pass between
/// otherwise. After each substep a sample inside the margin is moved out along the collider's
/// normal by the smallest mass-weighted change of the control vertices that carry it.
#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <vector>

#include "colliders.hpp"
#include "lattice.hpp"

namespace thinburn {

/// @brief The sample points: sample s is at sum_k weight[s, k] * x(vertex[s, k]).
struct ContactSamples {
  int stencil = 0;             ///< control vertices per sample
  std::vector<int> vertex;     ///< size() * stencil control vertex indices
  std::vector<double> weight;  ///< size() * stencil weights, each sample's sum to 1 (0: an unused slot)
  /// Samples [group[g], group[g + 1]) have the same vertices (a control cell's stencil): the
  /// convex hull of those vertices holds them all, so one query tells whether any can touch.
  std::vector<int> group;
  double spacing = 0.0;        ///< m between neighbouring samples at rest (the finest feature caught)
  /// The largest sum of |weight| of a sample: 1 where the weights are >= 0 (a sample then lies
  /// in its vertices' convex hull); an MLS embedding's negative weights can carry it beyond.
  double spread = 1.0;
  int size() const { return stencil ? static_cast<int>(vertex.size()) / stencil : 0; }
  bool empty() const { return size() == 0; }
};

class ShellContact {
 public:
  explicit ShellContact(ContactSamples samples);
  const ContactSamples& samples() const { return s_; }

  /// @brief After a substep h (after the control vertices' own contacts): each sample closer than
  /// margin to a collider moves out to it along the normal, loses its inward normal speed
  /// relative to the collider and, by the collider's friction times that, its tangential one;
  /// its move along the collider since x_begin (the positions at the substep's start) is held
  /// back by up to the friction times the push. Only the vertices with slot[v] >= 0 (integrated
  /// this step) move. Returns the samples moved.
  int apply(const Colliders& colliders, const ColliderMotion& motion, double margin, double h,
            const RowMatX3& x_begin, RowMatX3& x, RowMatX3& vel, const Eigen::VectorXd& mass,
            const std::vector<int>& slot);

  /// @brief Substeps of a step dt (>= 1) that the samples need: where they held a stencil in the
  /// last substep, the solve (which does not know the collider) lets the whole sheet fall, and
  /// the push back moves only the stencils in contact, straining their springs to the rest by
  /// the fall over their length; a stencil moving into a collider must not pass too far within a
  /// substep. shortest(v) is vertex v's shortest spring in the sheet's plane.
  double substeps(const Colliders& colliders, double margin, double dt, double g, const RowMatX3& x,
                  const RowMatX3& vel, const std::vector<int>& slot,
                  const std::function<double(int)>& shortest) const;
  /// @brief A substep starts: forget the pushes on the vertices it moves (slot[v] >= 0).
  void begin_substep(const std::vector<int>& slot);

 private:
  bool group_may_touch(int g, const Colliders& colliders, double margin, const RowMatX3& x,
                       const std::vector<int>& slot) const;
  bool push_out(int s, const Colliders& colliders, const ColliderMotion& motion, double margin, double h,
                const RowMatX3& x_begin, RowMatX3& x, RowMatX3& vel, const Eigen::VectorXd& mass,
                const std::vector<int>& slot);
  void hold(int v, const Eigen::Vector3d& push);

  ContactSamples s_;
  std::vector<double> share_;  // scratch: per stencil vertex, w m^-1 / sum w^2 m^-1
  // Per control vertex (sized on the first apply): the sum of its share of each push of the
  // last substep that moved it times the push's depth along the push's normal; valid where
  // listed_. support_list_ holds the listed vertices, so a substep forgets them in O(listed).
  RowMatX3 support_;
  std::vector<std::uint8_t> listed_;
  std::vector<int> support_list_;
};

}  // namespace thinburn
