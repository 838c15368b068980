#include "threads.hpp"

#include <algorithm>
#include <atomic>
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

}  // namespace thinburn
