// The extension module: one define_* call per part of the model.
#include "bindings.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "thinburn C++ core";
  thinburn::bind::define_threads(m);
  thinburn::bind::define_fire_front(m);
  thinburn::bind::define_simulation(m);
  thinburn::bind::define_particles(m);
  thinburn::bind::define_heat(m);
  thinburn::bind::define_lattice(m);
  thinburn::bind::define_dynamics(m);
  thinburn::bind::define_surface_front(m);
  thinburn::bind::define_bending(m);
  thinburn::bind::define_control_surface(m);
  thinburn::bind::define_colliders(m);
  thinburn::bind::define_param_table(m);
}
