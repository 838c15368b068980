#include "bindings.hpp"
#include "threads.hpp"

namespace py = pybind11;

namespace thinburn::bind {
void define_threads(py::module_& m) {
  m.def("has_openmp", &has_openmp, "Whether the core was built with OpenMP.");
  m.def("set_num_threads", &set_num_threads, py::arg("n"),
        "Set the number of threads the core uses (>= 1).");
  m.def("num_threads", &num_threads, "The number of threads the core uses.");
  m.def("max_hardware_threads", &max_hardware_threads,
        "Logical cores the OpenMP runtime sees (1 without OpenMP).");
}
}  // namespace thinburn::bind
