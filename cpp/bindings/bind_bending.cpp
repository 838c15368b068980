// Thin binding of Bending (eqs 2-6): heat, pyrolysis and the rotation D per couple.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "bending.hpp"
#include "bindings.hpp"
#include "kwargs.hpp"

namespace py = pybind11;

namespace thinburn::bind {

namespace {
void require_rows(const RowMatX3& m, Eigen::Index rows, const char* name) {
  if (m.rows() != rows)
    throw py::value_error(std::string(name) + " must have " + std::to_string(rows) + " rows (2 per couple), got " +
                          std::to_string(m.rows()));
  if (!m.allFinite()) throw py::value_error(std::string(name) + " must be finite");
}
}  // namespace

void define_bending(py::module_& m) {
  py::class_<Bending>(m, "Bending",
                      "Heat (eq 2), pyrolysis (eq 3) and the rotation D (eqs 4-6) of a lattice's "
                      "couples; keyword arguments ct, cp, alpha, beta, d_min, pyrolysis_range, max_rotation, "
                      "heat_tolerance, heat_fast (docs/bending.md).")
      .def(py::init([](int couples, const py::kwargs& kw) {
             if (couples < 1) throw py::value_error("couples must be >= 1, got " + std::to_string(couples));
             BendingParams p;
             apply_kwargs(p, kw, "bending");
             return new Bending(couples, p);
           }),
           py::arg("couples"))
      .def(
          "add_particle_heat",
          [](Bending& b, const RowMatX3& control, const RowMatX3& particles, const Eigen::VectorXd& temperature,
             double dt) {
            require_rows(control, b.heat().size(), "control");
            if (temperature.size() != particles.rows())
              throw py::value_error("temperature must have one entry per particle (" +
                                    std::to_string(particles.rows()) + "), got " + std::to_string(temperature.size()));
            if (!particles.allFinite() || !temperature.allFinite())
              throw py::value_error("particles and temperature must be finite");
            if (!(dt > 0) || !std::isfinite(dt)) throw py::value_error("dt must be finite and > 0");
            py::gil_scoped_release release;
            b.add_particle_heat(control, particles, temperature, dt);
          },
          py::arg("control"), py::arg("particles"), py::arg("temperature"), py::arg("dt"),
          "Eq 2: add the heat the particles give the control vertices (2 M^2 x 3) over dt.")
      .def(
          "set_pyrolysis",
          [](Bending& b, const RowMatX3& control, const RowMatX3& ignition_points) {
            require_rows(control, b.heat().size(), "control");
            if (!ignition_points.allFinite()) throw py::value_error("ignition_points must be finite");
            py::gil_scoped_release release;
            b.set_pyrolysis(control, ignition_points);
          },
          py::arg("control"), py::arg("ignition_points"), "Eq 3: pyrolysis from the ignition points, recomputed.")
      .def(
          "rotation",
          [](const Bending& b) {
            Eigen::VectorXd d;
            b.rotation(d);
            return d;
          },
          "Eqs 4-6: D per couple, radians, saturated at max_rotation.")
      .def_property_readonly("heat", &Bending::heat, "Heat accumulated per control vertex (eq 2).")
      .def_property_readonly("heat_rate", &Bending::heat_rate, "The last step's heat / dt per control vertex.")
      .def_property_readonly("pyrolysis", &Bending::pyrolysis, "Pyrolysis per control vertex now (eq 3).")
      .def_property_readonly("params", [](const Bending& b) { return params_dict(b.params()); });
}

}  // namespace thinburn::bind
