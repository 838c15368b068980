#pragma once
/// @brief Which control vertices a step of the lattice integrates (docs/dynamics.md §5): the
/// awake ones. A vertex falls asleep when it, and its spring neighbours, are slow and its net
/// force would not make it fast within a step; it wakes when something forces it, when a
/// moving neighbour stresses it, or when a set_* call changes what acts on it.
#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <vector>

#include "lattice.hpp"

namespace thinburn {

struct DynamicsParams;

/// Steps: the longest flicker hold (and DynamicsParams::wake_hold's upper bound).
constexpr int kMaxHold = 10000;

class Sleeping {
 public:
  /// @brief A speed vertex v would reach within the step, moved by its net force at the current
  /// state (the floor's and colliders' reactions taken out).
  using Speed = std::function<double(int v)>;

  /// @brief n control vertices, all awake. The arguments are kept by reference: the springs'
  /// incidence, the pinned flags and the parameters of the dynamics that owns this.
  Sleeping(int n, const SpringIncidence& incidence, const std::vector<std::uint8_t>& pinned,
           const DynamicsParams& p);

  void wake(int v) { awake_[v] = 1; }
  void wake_all();
  /// @brief 1 where a vertex is awake (pinned ones included).
  const std::vector<std::uint8_t>& awake() const { return awake_; }
  /// @brief Steps each flickering vertex still stays awake, and the length of its last hold.
  const std::vector<std::uint16_t>& hold() const { return hold_; }
  const std::vector<std::uint16_t>& hold_len() const { return hold_len_; }
  /// @brief Put back what awake(), hold() and hold_len() returned (a step that threw).
  void restore(std::vector<std::uint8_t>&& awake, std::vector<std::uint16_t>&& hold,
               std::vector<std::uint16_t>&& hold_len);

  /// @brief Per vertex: forced this step (a crumple, or a heat change that would reach
  /// sleep_speed within it); set by the step before wake_around_forcing.
  std::vector<std::uint8_t>& forced() { return forced_; }

  /// @brief The awake, unpinned vertices, in index order, and each vertex's position among
  /// them (-1 when not active); valid after collect_active.
  const std::vector<int>& active() const { return active_; }
  const std::vector<int>& slot() const { return slot_; }
  void collect_active();

  /// @brief Wake the forced vertices with two rings of spring neighbours, the awake ones
  /// moving at sleep_speed or faster with one.
  void wake_around_forcing(const RowMatX3& vel);
  /// @brief Wake the sleepers next to an active vertex that would reach sleep_speed within the
  /// step, their springs to the rest of the sheet holding them back (held); returns how many woke.
  int wake_stressed_sleepers(const Speed& held);
  /// @brief At a step's end: put the quiet active vertices to sleep (velocity and the implicit
  /// warm start accel zeroed), when they are a region and not stragglers. free: the speed its
  /// net force alone would give a vertex within the step (nothing holding it back).
  void update_sleep(RowMatX3& vel, RowMatX3& accel, const Speed& free);
  /// @brief Count a step (a sleeper woken within wake_hold steps of falling asleep flickers).
  void end_step() { ++steps_; }

 private:
  void wake_rings(std::vector<std::uint8_t>& flag, int rings) const;

  int n_;
  const SpringIncidence& inc_;
  const std::vector<std::uint8_t>& pinned_;
  const DynamicsParams& p_;
  std::vector<std::uint8_t> awake_, forced_;
  std::vector<std::uint16_t> hold_;      // steps a flickering sleeper still stays awake
  std::vector<std::uint16_t> hold_len_;  // the length of its last hold (doubles per flicker)
  std::vector<std::int64_t> slept_at_;   // step at which each vertex last fell asleep
  std::int64_t steps_ = 0;               // steps taken
  std::vector<int> active_, slot_;       // active vertices; slot_[v] = position in active_ or -1
  std::vector<std::uint8_t> mark_;       // scratch flags, all zero between uses
  std::vector<int> list_;                // scratch vertex list
};

}  // namespace thinburn
