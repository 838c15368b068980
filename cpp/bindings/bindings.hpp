#pragma once
#include <pybind11/pybind11.h>

#include "bending.hpp"
#include "dynamics.hpp"
#include "particles.hpp"

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

// Parameter structs from keyword dictionaries (unknown names raise TypeError, bad values
// ValueError naming the field), shared by the parts' own bindings and the Simulation's.
void apply_dynamics_kwargs(DynamicsParams& p, const pybind11::dict& kw);
pybind11::dict dynamics_params_dict(const DynamicsParams& p);
void apply_particle_kwargs(ParticleParams& p, const pybind11::dict& kw);
pybind11::dict particle_params_dict(const ParticleParams& p);
void apply_bending_kwargs(BendingParams& p, const pybind11::dict& kw);
pybind11::dict bending_params_dict(const BendingParams& p);
}  // namespace thinburn::bind
