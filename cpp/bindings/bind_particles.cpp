#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "kwargs.hpp"
#include "particles.hpp"

namespace py = pybind11;

namespace thinburn::bind {
void define_particles(py::module_& m) {
  py::class_<ParticleSystem>(m, "ParticleSystem",
                             "A fixed-capacity pool of fire particles, structure of arrays, "
                             "deterministic. A birth that finds the pool full is dropped and "
                             "counted in `dropped`.")
      .def(py::init([](const py::kwargs& kw) {
             ParticleParams p;
             apply_kwargs(p, kw, "particle");
             return new ParticleSystem(p);
           }),
           "Create an empty pool; keyword arguments are the ParticleParams fields (param_fields('particles'));\n"
           "raises ValueError naming a bad parameter.")
      .def(
          "emit",
          [](ParticleSystem& s, const RowMatX3& pos, const RowMatX3& normal,
             const Eigen::VectorXd& length, double dt) {
            py::gil_scoped_release release;
            s.emit(pos, normal, length, dt);
          },
          py::arg("pos"), py::arg("normal"), py::arg("length"), py::arg("dt"),
          "Emit particles for one step of length dt from emitters at pos (k x 3) with sheet "
          "normals (k x 3) and front lengths (k, m); expected births birth_rate*length*dt.")
      .def(
          "step",
          [](ParticleSystem& s, double dt, const Eigen::Vector3d& wind) {
            py::gil_scoped_release release;
            s.step(dt, wind);
          },
          py::arg("dt"), py::arg("wind"),
          "Advance all live particles by dt in a wind (m/s): cool, drag, buoyancy, "
          "turbulence, age, kill the dead.")
      .def("positions", [](const ParticleSystem& s) { return RowMatX3(s.positions()); },
           "Live positions (count x 3), m (a copy).")
      .def("velocities", [](const ParticleSystem& s) { return RowMatX3(s.velocities()); },
           "Live velocities (count x 3), m/s (a copy).")
      .def("temperatures", [](const ParticleSystem& s) { return Eigen::VectorXd(s.temperatures()); },
           "Live temperatures (count), K above ambient (a copy).")
      .def("ages", [](const ParticleSystem& s) { return Eigen::VectorXd(s.ages()); },
           "Live ages (count), s (a copy).")
      .def("lifetimes", [](const ParticleSystem& s) { return Eigen::VectorXd(s.lifetimes()); },
           "Live lifetimes (count), s: a particle dies when its age reaches this (a copy).")
      .def("ids", [](const ParticleSystem& s) { return s.ids(); },
           "Birth serial numbers of the live particles.")
      .def_property_readonly("count", &ParticleSystem::count, "Number of live particles.")
      .def_property_readonly("capacity", &ParticleSystem::capacity, "Pool capacity.")
      .def_property_readonly("dropped", &ParticleSystem::dropped,
                             "Births refused because the pool was full, since construction.")
      .def_property_readonly("born", &ParticleSystem::born,
                             "Particles born since construction (including those that died).")
      .def_property_readonly("steps", &ParticleSystem::steps, "Steps taken since construction.")
      .def_property_readonly(
          "params", [](const ParticleSystem& s) { return params_dict(s.params()); },
          "The parameters in force, as a dict.");
}
}  // namespace thinburn::bind
