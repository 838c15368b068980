#pragma once
/// @brief Wall-clock seconds spent in each phase of a simulation's frames, summed since it was
/// built: the per-phase profile of scripts/bench_film.py (docs/bench.md, "film"). A phase
/// costs two clock reads (tens of nanoseconds) per step; nothing in the model reads them.
#include <array>
#include <chrono>
#include <cstddef>

namespace thinburn {

enum class Phase : std::size_t {
  FireFront,  ///< the front's advance (eq 1) and the pace of a timed burn
  Cells,      ///< cell states: burnt cells retired, heat ignition
  Sources,    ///< the fringe's emitters and the ignition points handed to the shell
  Particles,  ///< fire particles born and moved
  Heat,       ///< eq 2's heat, eq 3's pyrolysis and D (eqs 4-6) at the couples
  Dynamics,   ///< masses, strength and the lattice's motion (eqs 7-15)
  Mesh,       ///< the mesh's vertices deformed by the lattice (vertex_positions)
  Count
};

constexpr std::size_t kPhases = static_cast<std::size_t>(Phase::Count);

/// @brief The phases' names, in Phase's order (the Python dict's keys).
inline const char* phase_name(Phase p) {
  static const char* names[kPhases] = {"fire_front", "cells", "sources", "particles",
                                       "heat", "dynamics", "mesh"};
  return names[static_cast<std::size_t>(p)];
}

struct PhaseTimes {
  std::array<double, kPhases> seconds{};
  double& operator[](Phase p) { return seconds[static_cast<std::size_t>(p)]; }
  double operator[](Phase p) const { return seconds[static_cast<std::size_t>(p)]; }
};

/// @brief Adds the seconds from its construction to its destruction to one phase.
class PhaseTimer {
 public:
  PhaseTimer(PhaseTimes& times, Phase p) : slot_(times[p]), start_(std::chrono::steady_clock::now()) {}
  ~PhaseTimer() { slot_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  PhaseTimer(const PhaseTimer&) = delete;
  PhaseTimer& operator=(const PhaseTimer&) = delete;

 private:
  double& slot_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace thinburn
