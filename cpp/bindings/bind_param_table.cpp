// The parameter tables (param_table.hpp) for Python: param_fields(group) describes a struct's
// fields, from which python/thinburn/params.py derives the key lists and bounds.
#include <pybind11/pybind11.h>

#include <string>

#include "bindings.hpp"
#include "kwargs.hpp"
#include "simulation.hpp"

namespace py = pybind11;

namespace thinburn::bind {

void define_param_table(py::module_& m) {
  m.def(
      "param_fields",
      [](const std::string& group) {
        if (group == "simulation") return describe_fields<SimulationParams>();
        if (group == "shell") return describe_fields<ShellParams>();
        if (group == "dynamics") return describe_fields<DynamicsParams>();
        if (group == "particles") return describe_fields<ParticleParams>();
        if (group == "bending") return describe_fields<BendingParams>();
        throw py::value_error("group must be 'simulation', 'shell', 'dynamics', 'particles' or 'bending', got '" +
                              group + "'");
      },
      py::arg("group"),
      "The fields of a parameter struct, in order: per field a dict of name, kind (real, int, "
      "seed, flag, vector, choice), default, low, high (None: no bound), low_open, high_open, "
      "choices and doc.");
}

}  // namespace thinburn::bind
