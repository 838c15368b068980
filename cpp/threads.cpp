#include "threads.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <limits>
#include <memory>
#include <string>
#include <stdexcept>

#ifdef THINBURN_HAVE_OPENMP
#include <omp.h>
#endif

namespace thinburn {
namespace {
std::atomic<int> g_threads{1};
}

bool has_openmp() {
#ifdef THINBURN_HAVE_OPENMP
  return true;
#else
  return false;
#endif
}

int max_hardware_threads() {
#ifdef THINBURN_HAVE_OPENMP
  return std::max(1, omp_get_num_procs());
#else
  return 1;
#endif
}

void set_num_threads(int n) {
  if (n < 1) throw std::invalid_argument("threads must be >= 1");
  g_threads = n;
}

int num_threads() { return g_threads; }

namespace {

// One pass of the triad; the same static schedule as the first touch, so each thread streams
// the pages it touched first.
double triad_seconds(double* a, const double* b, const double* c, std::ptrdiff_t n, double s) {
  const auto t0 = std::chrono::steady_clock::now();
#ifdef THINBURN_HAVE_OPENMP
#pragma omp parallel for num_threads(thinburn::num_threads()) schedule(static)
#endif
  for (std::ptrdiff_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

double measure_memory_bandwidth(std::size_t bytes, int repeat) {
  constexpr std::size_t kMinBytes = 3 * sizeof(double) * 1024;
  if (bytes < kMinBytes)
    throw std::invalid_argument("bytes must be >= " + std::to_string(kMinBytes) + ", got " +
                                std::to_string(bytes));
  if (repeat < 1) throw std::invalid_argument("repeat must be >= 1, got " + std::to_string(repeat));
  const auto n = static_cast<std::ptrdiff_t>(bytes / (3 * sizeof(double)));
  // Uninitialised storage, first touched by the threads that stream it.
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]), c(new double[n]);
#ifdef THINBURN_HAVE_OPENMP
#pragma omp parallel for num_threads(thinburn::num_threads()) schedule(static)
#endif
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    a[i] = 0.0;
    b[i] = 1.0;
    c[i] = 2.0;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < repeat; ++k) best = std::min(best, triad_seconds(a.get(), b.get(), c.get(), n, 0.5 + k));
  // The result is read so the passes cannot be dropped as dead stores.
  if (!(a[n / 2] > 0.0) || !(best > 0.0)) throw std::runtime_error("memory bandwidth probe failed");
  return 3.0 * sizeof(double) * static_cast<double>(n) / best;
}

}  // namespace thinburn
