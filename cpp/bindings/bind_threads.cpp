#include <pybind11/stl.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "threads.hpp"

namespace py = pybind11;

namespace thinburn::bind {
void define_threads(py::module_& m) {
  m.def("set_num_threads", &set_num_threads, py::arg("n"),
        "Set the default number of threads the core uses (1..max_threads()).");
  m.def("num_threads", &num_threads, "The number of threads the core uses on the calling thread.");
  m.def("hardware_threads", &hardware_threads, "Logical cores of this machine.");
  m.def("max_threads", &max_threads, "The largest thread count accepted (4 x the logical cores, at least 8).");
  m.def(
      "measure_memory_bandwidth",
      [](long long bytes, int repeat) {
        // Checked here too: a negative count must not wrap around to a huge size_t.
        if (bytes < 0) throw std::invalid_argument("bytes must be >= 0, got " + std::to_string(bytes));
        py::gil_scoped_release release;
        return measure_memory_bandwidth(static_cast<std::size_t>(bytes), repeat);
      },
      py::arg("bytes"), py::arg("repeat"),
      "Machine probe: sustained memory bandwidth (bytes/s) of a STREAM-style triad a = b + s c "
      "over three double arrays of `bytes` in all (>= 24576), on the core's threads, fastest of "
      "`repeat` passes; 24 bytes counted per element (two reads, one write).");
  m.def(
      "parallel_sum_check",
      [](long n, long cost, int threads, long throw_at) {
        // For tests of parallel_for itself: every item writes its own slot; one may throw.
        std::vector<long> out(static_cast<std::size_t>(std::max(0L, n)), 0);
        {
          py::gil_scoped_release release;
          ScopedThreads scope(threads);
          parallel_for(0, n, cost, [&](long i) {
            if (i == throw_at) throw std::runtime_error("item " + std::to_string(i) + " failed");
            out[static_cast<std::size_t>(i)] = i + 1;
          });
        }
        return out;
      },
      py::arg("n"), py::arg("cost"), py::arg("threads"), py::arg("throw_at") = -1,
      "Test hook: runs parallel_for over n items of `cost` on `threads` threads; item i writes "
      "i + 1 to its slot; item `throw_at` raises RuntimeError.");
}
}  // namespace thinburn::bind
