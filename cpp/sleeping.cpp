#include "sleeping.hpp"

#include <algorithm>
#include <limits>

#include "dynamics.hpp"
#include "threads.hpp"

namespace thinburn {
namespace {
constexpr int kSleepShare = 10;  // vertices fall asleep only when over 1/10 of the awake set is quiet
// A sleeper wakes once its held speed reaches sleep_speed / kHeldMargin. The held speed counts
// its anchors only and misses how the sheet moves as a whole; with the margin, a 1 m paper sheet
// burning on a table for 60 s ends within 2 um of the run without sleeping, against 0.14 mm
// without it (and 3.7 um with the free speed, which keeps 1.7x as many vertices awake).
constexpr double kHeldMargin = 10.0;
}  // namespace

Sleeping::Sleeping(int n, const SpringIncidence& incidence, const std::vector<std::uint8_t>& pinned,
                   const DynamicsParams& p)
    : n_(n), inc_(incidence), pinned_(pinned), p_(p) {
  st_.awake.assign(n_, 1);
  forced_.assign(n_, 0);
  st_.hold.assign(n_, 0);
  st_.hold_len.assign(n_, 0);
  st_.slept_at.assign(n_, std::numeric_limits<std::int64_t>::min() / 2);
  mark_.assign(n_, 0);
  list_.reserve(n_);
  slot_.assign(n_, -1);
  active_.reserve(n_);
}

void Sleeping::wake_all() { std::fill(st_.awake.begin(), st_.awake.end(), 1); }

void Sleeping::collect_active() {
  active_.clear();
  std::fill(slot_.begin(), slot_.end(), -1);
  for (int v = 0; v < n_; ++v)
    if (st_.awake[v] && !pinned_[v]) {
      slot_[v] = static_cast<int>(active_.size());
      active_.push_back(v);
    }
}

void Sleeping::wake_rings(std::vector<std::uint8_t>& flag, int rings) const {
  // flag: 1 = seed; grows by spring neighbours `rings` times (2 marks the new ring).
  for (int r = 0; r < rings; ++r) {
    for (int v = 0; v < n_; ++v)
      if (flag[v] == 1)
        for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q)
          if (!flag[inc_.other[q]]) flag[inc_.other[q]] = 2;
    for (auto& f : flag)
      if (f == 2) f = 1;
  }
}

void Sleeping::wake_around_forcing(const RowMatX3& vel) {
  // Forced vertices (a crumple, or a heat change that would reach sleep_speed within the step)
  // wake with two rings of spring neighbours; moving ones with one ring.
  std::vector<std::uint8_t>& seed = mark_;
  for (int v = 0; v < n_; ++v) seed[v] = forced_[v];
  wake_rings(seed, 1);
  for (int v = 0; v < n_; ++v)
    if (st_.awake[v] && vel.row(v).norm() >= p_.sleep_speed) seed[v] = 1;
  wake_rings(seed, 1);
  for (int v = 0; v < n_; ++v) {
    if (seed[v]) st_.awake[v] = 1;
    seed[v] = 0;
  }
}

void Sleeping::wake_flickering(int v) {
  st_.awake[v] = 1;
  // Woken within wake_hold steps of falling asleep: it flickers, so it stays awake, each time it
  // flickers again twice as long (up to kMaxHold steps).
  if (st_.steps - st_.slept_at[v] <= p_.wake_hold) {
    st_.hold_len[v] = static_cast<std::uint16_t>(std::clamp(2 * int(st_.hold_len[v]), p_.wake_hold, kMaxHold));
    st_.hold[v] = st_.hold_len[v];
  } else {
    st_.hold_len[v] = 0;
  }
}

int Sleeping::wake_stressed_sleepers(const Speed& held) {
  list_.clear();
  for (int v : active_)
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
      const int o = inc_.other[q];
      if (!st_.awake[o] && !pinned_[o] && !mark_[o]) {
        mark_[o] = 1;
        list_.push_back(o);
      }
    }
  int woke = 0;
  for (int o : list_) {
    mark_[o] = 0;
    for (State::Batch& b : st_.batches) b.pass_border += st_.slept_at[o] == b.step;
    if (held(o) * kHeldMargin >= p_.sleep_speed) {
      wake_flickering(o);
      ++woke;
      for (State::Batch& b : st_.batches) b.pass_woken += st_.slept_at[o] == b.step;
    }
  }
  // A batch of which one pass stressed awake most of the sleepers it checked (half or more of
  // those bordering the active set), enough to redo the step, within wake_hold steps of its
  // falling asleep, fell asleep in a sheet that is not at rest: a hanging curtain burning at
  // its hem moves by less than sleep_speed everywhere, but each change of load travels up to
  // the pins, waking the ring of sleepers next to the moving part a pass (60-92 % of it on the
  // half-size curtain of tests/test_sleeping.py, counted with a probe here). The rest of the
  // batch wakes with it, at once rather than in a wave of passes, and new batches wait. Where a
  // region rests on a floor, the floor holds most of its border (a hot spot growing on a lying
  // sheet woke 15 % of it), and the stragglers that wake keep their own hold.
  for (State::Batch& b : st_.batches) {
    const int pass_woken = b.pass_woken, pass_border = b.pass_border;
    b.pass_woken = b.pass_border = 0;
    if (b.flickered || pass_woken == 0 || st_.steps - b.step > p_.wake_hold ||
        pass_woken * kRedoShare < static_cast<int>(active_.size()) || 2 * pass_woken < pass_border)
      continue;
    b.flickered = true;
    for (int v = 0; v < n_; ++v)
      if (!st_.awake[v] && st_.slept_at[v] == b.step) {
        wake_flickering(v);
        ++woke;
      }
    st_.batch_hold = std::clamp(2 * st_.batch_hold, p_.wake_hold, kMaxHold);
    st_.flicker_at = st_.steps;
  }
  return woke;
}

void Sleeping::update_sleep(RowMatX3& vel, RowMatX3& accel, const Speed& free) {
  const int na = static_cast<int>(active_.size());
  // A vertex sleeps when it, and every spring neighbour, is slower than sleep_speed, it was not
  // forced this step, and its net force (floor reaction included) would not bring it to
  // sleep_speed within a step even if nothing held it back. It wakes only once the force would
  // do so against its springs (wake_stressed_sleepers): falling asleep is strict, waking
  // lenient, so a sleeper is not woken by the force it fell asleep with.
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = active_[a];
    if (st_.hold[v] > 0) --st_.hold[v];
    bool quiet = st_.hold[v] == 0 && !forced_[v] && vel.row(v).norm() < p_.sleep_speed;
    for (int q = inc_.start[v]; quiet && q < inc_.start[v + 1]; ++q)
      quiet = vel.row(inc_.other[q]).norm() < p_.sleep_speed;
    if (quiet) quiet = free(v) < p_.sleep_speed;
    mark_[v] = quiet ? 1 : 0;
  });
  // Regions sleep, not stragglers: when the quiet vertices are under 1/kSleepShare of the awake
  // set, none sleeps this step. A few sleepers inside a moving sheet save little and cost a
  // redone step or a new factorization each time the motion stresses them awake.
  int quiet_count = 0;
  for (int v : active_) quiet_count += mark_[v];
  // Batches that stayed asleep past wake_hold steps are forgotten; one that did clears the hold.
  for (const State::Batch& b : st_.batches)
    if (st_.steps - b.step > p_.wake_hold && !b.flickered) st_.batch_hold = 0;
  st_.batches.erase(std::remove_if(st_.batches.begin(), st_.batches.end(),
                                [&](const State::Batch& b) { return st_.steps - b.step > p_.wake_hold; }),
                 st_.batches.end());
  const bool bulk = quiet_count > 0 && quiet_count * kSleepShare >= na && st_.steps - st_.flicker_at >= st_.batch_hold;
  if (bulk) st_.batches.push_back({st_.steps, 0, 0, false});
  for (int v : active_) {
    if (mark_[v] && bulk) {
      st_.awake[v] = 0;
      st_.slept_at[v] = st_.steps;
      vel.row(v).setZero();
      accel.row(v).setZero();
    }
    mark_[v] = 0;
  }
}

}  // namespace thinburn
