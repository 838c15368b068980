#pragma once
/// @brief Explicit thread count for every OpenMP loop in the core.
///
/// The core never relies on OMP_NUM_THREADS: callers set the count, and every
/// parallel loop asks for it with num_threads(). Results never depend on it.
namespace thinburn {

/// @brief Whether the core was built with OpenMP.
bool has_openmp();

/// @brief Set the number of threads used by the core (>= 1).
void set_num_threads(int n);

/// @brief The number of threads the core uses.
int num_threads();

/// @brief Number of logical cores the OpenMP runtime sees (1 without OpenMP).
int max_hardware_threads();

}  // namespace thinburn
