#pragma once
/// @brief Explicit thread count for every OpenMP loop in the core.
///
/// The core never relies on OMP_NUM_THREADS: callers set the count, and every
/// parallel loop asks for it with num_threads(). Results never depend on it.
#include <cstddef>

namespace thinburn {

/// @brief Loops with less work than this (in units of a few flops: items times their inner
/// size) run on one thread. Starting and joining a team costs microseconds, and much more when
/// the other core is busy (a team member waits for the scheduler); the small loops of a
/// 128-cell frame gain nothing from a second thread.
constexpr long kParallelWork = 1L << 15;

/// @brief Whether a loop of `work` units is worth a team of threads.
inline bool worth_threads(long work) { return work >= kParallelWork; }

/// @brief Whether the core was built with OpenMP.
bool has_openmp();

/// @brief Set the number of threads used by the core (>= 1).
void set_num_threads(int n);

/// @brief The number of threads the core uses.
int num_threads();

/// @brief Number of logical cores the OpenMP runtime sees (1 without OpenMP).
int max_hardware_threads();

/// @brief Machine probe: sustained memory bandwidth of a STREAM-style triad a = b + s c on
/// num_threads() threads.
/// @param bytes total size of the three double arrays (>= 3 * 8 * 1024); to measure main
/// memory, make it several times the last-level cache.
/// @param repeat timed passes (>= 1); the fastest is kept.
/// @return bytes moved per second, counted as STREAM does: 24 bytes per element (two reads,
/// one write; the write-allocate read of a is not counted).
double measure_memory_bandwidth(std::size_t bytes, int repeat);

}  // namespace thinburn
