#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "convert.hpp"
#include "particles.hpp"

namespace py = pybind11;

namespace thinburn::bind {
namespace {

ParticleSystem make_system(int capacity, double birth_rate, double temperature0, double cooling,
                           double lifetime, double lifetime_jitter, double buoyancy, double drag,
                           double turbulence, double birth_speed, double vertical_band,
                           std::uint64_t seed) {
  ParticleParams p;
  p.capacity = capacity;
  p.birth_rate = birth_rate;
  p.temperature0 = temperature0;
  p.cooling = cooling;
  p.lifetime = lifetime;
  p.lifetime_jitter = lifetime_jitter;
  p.buoyancy = buoyancy;
  p.drag = drag;
  p.turbulence = turbulence;
  p.birth_speed = birth_speed;
  p.vertical_band = vertical_band;
  p.seed = seed;
  return ParticleSystem(p);
}

py::dict params_dict(const ParticleParams& p) {
  py::dict d;
  d["capacity"] = p.capacity;
  d["birth_rate"] = p.birth_rate;
  d["temperature0"] = p.temperature0;
  d["cooling"] = p.cooling;
  d["lifetime"] = p.lifetime;
  d["lifetime_jitter"] = p.lifetime_jitter;
  d["buoyancy"] = p.buoyancy;
  d["drag"] = p.drag;
  d["turbulence"] = p.turbulence;
  d["birth_speed"] = p.birth_speed;
  d["vertical_band"] = p.vertical_band;
  d["seed"] = p.seed;
  return d;
}

}  // namespace

void apply_particle_kwargs(ParticleParams& p, const py::dict& kw) {
  for (const auto& item : kw) {
    const std::string k = key_name(item.first);
    double* d = k == "birth_rate"        ? &p.birth_rate
                : k == "temperature0"    ? &p.temperature0
                : k == "cooling"         ? &p.cooling
                : k == "lifetime"        ? &p.lifetime
                : k == "lifetime_jitter" ? &p.lifetime_jitter
                : k == "buoyancy"        ? &p.buoyancy
                : k == "drag"            ? &p.drag
                : k == "turbulence"      ? &p.turbulence
                : k == "birth_speed"     ? &p.birth_speed
                : k == "vertical_band"   ? &p.vertical_band
                                         : nullptr;
    if (d)
      *d = to_double(k, item.second);
    else if (k == "capacity")
      p.capacity = to_int(k, item.second, 1, 100000000);
    else
      throw py::type_error("unexpected particle parameter '" + k + "'");
  }
  validate(p);
}

py::dict particle_params_dict(const ParticleParams& p) { return params_dict(p); }

void define_particles(py::module_& m) {
  const ParticleParams def;
  py::class_<ParticleSystem>(m, "ParticleSystem",
                             "A fixed-capacity pool of fire particles, structure of arrays, "
                             "deterministic. A birth that finds the pool full is dropped and "
                             "counted in `dropped`.")
      .def(py::init(&make_system), py::arg("capacity") = def.capacity,
           py::arg("birth_rate") = def.birth_rate, py::arg("temperature0") = def.temperature0,
           py::arg("cooling") = def.cooling, py::arg("lifetime") = def.lifetime,
           py::arg("lifetime_jitter") = def.lifetime_jitter, py::arg("buoyancy") = def.buoyancy,
           py::arg("drag") = def.drag, py::arg("turbulence") = def.turbulence,
           py::arg("birth_speed") = def.birth_speed, py::arg("vertical_band") = def.vertical_band,
           py::arg("seed") = def.seed,
           "Create an empty pool; raises ValueError naming a bad parameter.")
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
