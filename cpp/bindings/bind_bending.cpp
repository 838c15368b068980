// Thin binding of Bending (eqs 2-6): heat, pyrolysis and the rotation D per couple, and the
// keyword parser of its parameters, shared with the Simulation's.
#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "bending.hpp"
#include "bindings.hpp"
#include "convert.hpp"

namespace py = pybind11;

namespace thinburn::bind {

void apply_bending_kwargs(BendingParams& b, const py::dict& kw) {
  for (const auto& item : kw) {
    const std::string k = key_name(item.first);
    double* d = k == "ct" ? &b.ct : k == "cp" ? &b.cp : k == "alpha" ? &b.alpha : k == "beta" ? &b.beta
              : k == "d_min" ? &b.d_min : k == "heat_tolerance" ? &b.tolerance
              : k == "max_rotation" ? &b.max_rotation : nullptr;
    if (d)
      *d = to_double(k, item.second);
    else if (k == "heat_fast")
      b.fast = to_bool(k, item.second);
    else
      throw py::type_error("unexpected bending parameter '" + k + "'");
  }
  if (!(b.d_min > 0)) throw std::invalid_argument("d_min must be > 0");
  if (!(b.tolerance > 0 && b.tolerance < 1)) throw std::invalid_argument("heat_tolerance must be in (0, 1)");
  if (!(b.ct >= 0) || !(b.cp >= 0)) throw std::invalid_argument("ct and cp must be >= 0");
  if (!(b.max_rotation >= 0) || !std::isfinite(b.max_rotation)) throw std::invalid_argument("max_rotation must be >= 0");
  if (!std::isfinite(b.alpha) || !std::isfinite(b.beta)) throw std::invalid_argument("alpha and beta must be finite");
}

py::dict bending_params_dict(const BendingParams& b) {
  return py::dict(py::arg("ct") = b.ct, py::arg("cp") = b.cp, py::arg("alpha") = b.alpha,
                  py::arg("beta") = b.beta, py::arg("d_min") = b.d_min, py::arg("max_rotation") = b.max_rotation,
                  py::arg("heat_tolerance") = b.tolerance, py::arg("heat_fast") = b.fast);
}

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
                      "couples; keyword arguments ct, cp, alpha, beta, d_min, max_rotation, "
                      "heat_tolerance, heat_fast (docs/bending.md).")
      .def(py::init([](int couples, const py::kwargs& kw) {
             if (couples < 1) throw py::value_error("couples must be >= 1, got " + std::to_string(couples));
             BendingParams p;
             apply_bending_kwargs(p, kw);
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
      .def_property_readonly("params", [](const Bending& b) { return bending_params_dict(b.params()); });
}

}  // namespace thinburn::bind
