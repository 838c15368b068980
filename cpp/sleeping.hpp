#pragma once
/// @brief Which control vertices a step of the lattice integrates (docs/dynamics.md §5): the
/// awake ones. A vertex falls asleep when it, and its spring neighbours, are slow and its net
/// force would not make it fast within a step; it wakes when something forces it, when a
/// moving neighbour stresses it, or when a set_* call changes what acts on it.
#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "lattice.hpp"

namespace thinburn {

struct DynamicsParams;

/// Steps: the longest flicker hold (and DynamicsParams::wake_hold's upper bound).
constexpr int kMaxHold = 10000;
/// A step is redone when it stresses awake at least 1/kRedoShare of its awake count.
constexpr int kRedoShare = 16;

class Sleeping {
 public:
  /// @brief A speed vertex v would reach within the step, moved by its net force at the current
  /// state (the floor's and colliders' reactions taken out).
  using Speed = std::function<double(int v)>;

  /// @brief n control vertices, all awake. The arguments are kept by reference: the springs'
  /// incidence, the pinned flags and the parameters of the dynamics that owns this.
  Sleeping(int n, const SpringIncidence& incidence, const std::vector<std::uint8_t>& pinned,
           const DynamicsParams& p);

  void wake(int v) { st_.awake[v] = 1; }
  void wake_all();
  /// @brief 1 where a vertex is awake (pinned ones included).
  const std::vector<std::uint8_t>& awake() const { return st_.awake; }

  /// @brief Who sleeps and what the flicker holds remember: taken before a step that may
  /// throw, put back if it does.
  struct State {
    std::vector<std::uint8_t> awake;
    std::vector<std::uint16_t> hold;      // steps a flickering sleeper still stays awake
    std::vector<std::uint16_t> hold_len;  // the length of its last hold (doubles per flicker)
    std::vector<std::int64_t> slept_at;   // step at which each vertex last fell asleep
    std::int64_t steps = 0;               // steps taken
    // The region's flicker hold. Quiet vertices fall asleep together, a batch a step; a batch
    // of which one pass stresses awake most of the sleepers it checks, enough to redo the step,
    // within wake_hold steps, flickers: the rest of it wakes, and new batches wait batch_hold
    // steps (doubling per flicker, forgotten once a batch stays asleep past wake_hold).
    struct Batch {
      std::int64_t step;  // it fell asleep at the end of this step
      int pass_border;    // its sleepers next to the active set, checked by the pass in progress
      int pass_woken;     // ... and of those, the ones stressed awake
      bool flickered;
    };
    std::vector<Batch> batches;  // those that fell asleep within wake_hold steps
    std::int64_t flicker_at = std::numeric_limits<std::int64_t>::min() / 2;  // a batch last flickered
    int batch_hold = 0;
  };
  const State& state() const { return st_; }
  void restore(State&& s) { st_ = std::move(s); }

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
  void end_step() { ++st_.steps; }

 private:
  void wake_rings(std::vector<std::uint8_t>& flag, int rings) const;
  // Wake a sleeper stressed awake, with the flicker hold if it slept under wake_hold steps.
  void wake_flickering(int v);

  int n_;
  const SpringIncidence& inc_;
  const std::vector<std::uint8_t>& pinned_;
  const DynamicsParams& p_;
  State st_;
  std::vector<std::uint8_t> forced_;
  std::vector<int> active_, slot_;       // active vertices; slot_[v] = position in active_ or -1
  std::vector<std::uint8_t> mark_;       // scratch flags, all zero between uses
  std::vector<int> list_;                // scratch vertex list
};

}  // namespace thinburn
