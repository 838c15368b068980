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
  awake_.assign(n_, 1);
  forced_.assign(n_, 0);
  hold_.assign(n_, 0);
  hold_len_.assign(n_, 0);
  slept_at_.assign(n_, std::numeric_limits<std::int64_t>::min() / 2);
  mark_.assign(n_, 0);
  list_.reserve(n_);
  slot_.assign(n_, -1);
  active_.reserve(n_);
}

void Sleeping::wake_all() { std::fill(awake_.begin(), awake_.end(), 1); }

void Sleeping::restore(std::vector<std::uint8_t>&& awake, std::vector<std::uint16_t>&& hold,
                       std::vector<std::uint16_t>&& hold_len) {
  awake_ = std::move(awake);
  hold_ = std::move(hold);
  hold_len_ = std::move(hold_len);
}

void Sleeping::collect_active() {
  active_.clear();
  std::fill(slot_.begin(), slot_.end(), -1);
  for (int v = 0; v < n_; ++v)
    if (awake_[v] && !pinned_[v]) {
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
    if (awake_[v] && vel.row(v).norm() >= p_.sleep_speed) seed[v] = 1;
  wake_rings(seed, 1);
  for (int v = 0; v < n_; ++v) {
    if (seed[v]) awake_[v] = 1;
    seed[v] = 0;
  }
}

int Sleeping::wake_stressed_sleepers(const Speed& held) {
  list_.clear();
  for (int v : active_)
    for (int q = inc_.start[v]; q < inc_.start[v + 1]; ++q) {
      const int o = inc_.other[q];
      if (!awake_[o] && !pinned_[o] && !mark_[o]) {
        mark_[o] = 1;
        list_.push_back(o);
      }
    }
  int woke = 0;
  for (int o : list_) {
    mark_[o] = 0;
    if (held(o) * kHeldMargin >= p_.sleep_speed) {
      awake_[o] = 1;
      // Woken within wake_hold steps of falling asleep: it flickers, so it stays awake, each
      // time it flickers again twice as long (up to kMaxHold steps).
      if (steps_ - slept_at_[o] <= p_.wake_hold) {
        hold_len_[o] = static_cast<std::uint16_t>(std::clamp(2 * int(hold_len_[o]), p_.wake_hold, kMaxHold));
        hold_[o] = hold_len_[o];
      } else {
        hold_len_[o] = 0;
      }
      ++woke;
    }
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
    if (hold_[v] > 0) --hold_[v];
    bool quiet = hold_[v] == 0 && !forced_[v] && vel.row(v).norm() < p_.sleep_speed;
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
  const bool bulk = quiet_count * kSleepShare >= na;
  for (int v : active_) {
    if (mark_[v] && bulk) {
      awake_[v] = 0;
      slept_at_[v] = steps_;
      vel.row(v).setZero();
      accel.row(v).setZero();
    }
    mark_[v] = 0;
  }
}

}  // namespace thinburn
