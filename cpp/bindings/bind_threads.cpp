#include "bindings.hpp"
#include "threads.hpp"

#include <string>

namespace py = pybind11;

namespace thinburn::bind {
void define_threads(py::module_& m) {
  m.def("has_openmp", &has_openmp, "Whether the core was built with OpenMP.");
  m.def("set_num_threads", &set_num_threads, py::arg("n"),
        "Set the number of threads the core uses (>= 1).");
  m.def("num_threads", &num_threads, "The number of threads the core uses.");
  m.def("max_hardware_threads", &max_hardware_threads,
        "Logical cores the OpenMP runtime sees (1 without OpenMP).");
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
}
}  // namespace thinburn::bind
