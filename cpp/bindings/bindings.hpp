#pragma once
#include <pybind11/pybind11.h>

namespace thinburn::bind {
void define_threads(pybind11::module_& m);
void define_fire_front(pybind11::module_& m);
void define_simulation(pybind11::module_& m);
void define_particles(pybind11::module_& m);
void define_heat(pybind11::module_& m);
void define_lattice(pybind11::module_& m);
void define_dynamics(pybind11::module_& m);
void define_surface_front(pybind11::module_& m);
void define_bending(pybind11::module_& m);
void define_control_surface(pybind11::module_& m);
void define_colliders(pybind11::module_& m);
void define_param_table(pybind11::module_& m);
}  // namespace thinburn::bind
