// Thin binding of the Simulation; python/thinburn/simulation.py checks the arrays and arguments,
// the core the parameters (by their tables, param_table.hpp).
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "bindings.hpp"
#include "convert.hpp"
#include "kwargs.hpp"
#include "simulation.hpp"
#include "threads.hpp"

namespace py = pybind11;

namespace thinburn::bind {
namespace {

int checked_cell(const Simulation& s, int cell) {
  if (cell < 0 || cell >= s.num_cells())
    throw std::invalid_argument("cell: index " + std::to_string(cell) + " outside [0, " +
                                std::to_string(s.num_cells()) + ")");
  return cell;
}

// Per-cell values: (N, N) on the grid (geometry 'plane'), one per cell on a surface.
template <class T>
py::array_t<T> per_cell(const Simulation& s, const std::vector<T>& v) {
  py::array_t<T> a = s.geometry() == Geometry::Plane
                         ? py::array_t<T>({s.sheet().cells(), s.sheet().cells()})
                         : py::array_t<T>(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// The name of the geometry a Simulation chose, as the geometry keyword spells it.
std::string geometry_name(Geometry g) {
  return param::find_field(SimulationParams::fields(), "geometry")->choices.at(static_cast<int>(g));
}

void define_params(py::module_& m) {
  py::class_<SimulationParams> p(m, "SimulationParams", "Every scalar of a simulation (SI units).");
  p.def(py::init<>());
  // Its scalars, one property per field of its table (converted and named as keywords are;
  // the Simulation validates them all when it is built).
  for (const auto& f : SimulationParams::fields())
    p.def_property(
        f.name, [&f](const SimulationParams& s) { return get_field(f, s); },
        [&f](SimulationParams& s, const py::handle& v) { set_field(f, s, v); }, f.doc);
  p.def("set_dynamics", [](SimulationParams& s, const py::dict& kw) { apply_kwargs(s.dynamics, kw, "dynamics"); })
      .def("set_material",
           [](SimulationParams& s, const py::handle& k_structure, const py::handle& k_shear,
              const py::handle& k_flex, const py::handle& c_damping) {
             set_material(s.dynamics, to_double("K_structure", k_structure), to_double("K_shear", k_shear),
                          to_double("K_flex", k_flex), to_double("C_damping", c_damping));
           },
           py::arg("k_structure"), py::arg("k_shear"), py::arg("k_flex"), py::arg("c_damping"),
           "A Table 1 material's springs and damping, with the transverse springs and the crumple "
           "gain that follow from them (thinburn::set_material).")
      .def("validate", [](const SimulationParams& s) { validate(s); },
           "Raise ValueError naming the first invalid field (the groups' too), as building a Simulation does.")
      .def("set_particles", [](SimulationParams& s, const py::dict& kw) { apply_kwargs(s.particles, kw, "particle"); })
      .def("set_bending", [](SimulationParams& s, const py::dict& kw) { apply_kwargs(s.bending, kw, "bending"); })
      .def_property_readonly("dynamics", [](const SimulationParams& s) { return params_dict(s.dynamics); })
      .def_property_readonly("particles", [](const SimulationParams& s) { return params_dict(s.particles); })
      .def_property_readonly("bending", [](const SimulationParams& s) { return params_dict(s.bending); });
}

}  // namespace

void define_simulation(py::module_& m) {
  define_params(m);
  using S = Simulation;
  py::class_<S>(m, "Simulation", "The burning sheet, stepped in time.")
      .def(py::init([](const RowMatX3& v, const RowMatX3i& f, const RowMatX2& uv, const SimulationParams& p,
                       const std::vector<std::uint8_t>& pinned, const Eigen::VectorXd& speed_map,
                       const Eigen::VectorXd& fuel_map) {
             py::gil_scoped_release release;
             return new S(v, f, uv, p, pinned, CellMaps{speed_map, fuel_map});
           }),
           py::arg("vertices"), py::arg("faces"), py::arg("uv"), py::arg("params"), py::arg("pinned"),
           py::arg("speed_map"), py::arg("fuel_map"))
      .def("ignite", &S::ignite, py::arg("point"), py::arg("time"), py::arg("radius"),
           py::call_guard<py::gil_scoped_release>())
      .def("ignite_cells", &S::ignite_cells, py::arg("cells"), py::arg("time"),
           py::call_guard<py::gil_scoped_release>())
      .def("ignite_near", &S::ignite_near, py::arg("points"), py::arg("radius"), py::arg("time"),
           py::call_guard<py::gil_scoped_release>())
      .def("set_fire_sources", &S::set_fire_sources, py::arg("points"), py::arg("lengths"))
      .def("vertex_field", &S::vertex_field, py::arg("values"), py::call_guard<py::gil_scoped_release>())
      .def_property("speed_scale", &S::speed_scale, &S::set_speed_scale)
      .def("cells_near", &S::cells_near, py::arg("point"), py::arg("radius"),
           py::call_guard<py::gil_scoped_release>())
      .def("step",
           [](S& s, double dt, int threads) {
             // The Simulation's own count, for this call only: Simulations on other threads
             // keep theirs.
             py::gil_scoped_release release;
             ScopedThreads scope(threads);
             s.step(dt);
           },
           py::arg("dt"), py::arg("threads"))
      .def_property_readonly("time", &S::time)
      .def_property_readonly("params", [](const S& s) { return s.params(); },
                             "A copy of the parameters in force now.")
      .def_property("wind", &S::wind, &S::set_wind)
      .def("set_wind_field", &S::set_wind_field, py::arg("wind"))
      .def("set_colliders",
           [](S& s, std::shared_ptr<Colliders> c, double margin, int samples) {
             s.set_colliders(std::move(c), margin, samples);
           },
           py::arg("colliders").none(true), py::arg("margin"), py::arg("samples") = 0)
      .def_property_readonly("geometry", [](const S& s) { return geometry_name(s.geometry()); })
      .def_property_readonly("cells", [](const S& s) { return s.geometry() == Geometry::Plane ? s.sheet().cells() : s.params().cells; })
      .def_property_readonly("num_cells", &S::num_cells)
      .def_property_readonly("cell_spacing", [](const S& s) { return s.fire_cells().spacing(); })
      .def_property_readonly("cell_size", [](const S& s) {
        const bool plane = s.geometry() == Geometry::Plane;
        const double h = s.fire_cells().spacing();
        return py::make_tuple(plane ? s.sheet().dv() : h, plane ? s.sheet().du() : h);
      })
      .def_property_readonly("area", [](const S& s) { return s.fire_cells().total_area(); })
      .def("inside", [](const S& s) { return per_cell(s, s.fire_cells().inside()); })
      .def("cell_states", [](const S& s) { return per_cell(s, s.cell_states()); })
      .def("cell_temperature", [](const S& s) { return per_cell(s, s.cell_temperature().empty() ? std::vector<double>(s.num_cells(), 0.0) : s.cell_temperature()); })
      .def("firebreaks", [](const S& s) {
        std::vector<std::uint8_t> b(s.num_cells());
        for (int c = 0; c < s.num_cells(); ++c) b[c] = s.is_firebreak(c);
        return per_cell(s, b);
      })
      .def("ignition_times", [](const S& s) { return per_cell(s, s.ignition_times()); })
      .def("burn_durations", [](const S& s) { return per_cell(s, s.burn_durations()); })
      .def("cell_char", [](const S& s) { return per_cell(s, s.cell_char()); })
      .def("cell_mass", [](const S& s) { return per_cell(s, s.cell_mass()); })
      .def("cell_areas", [](const S& s) {
        std::vector<double> a(s.num_cells());
        for (int c = 0; c < s.num_cells(); ++c) a[c] = s.fire_cells().area(c);
        return per_cell(s, a);
      })
      .def("fringe", &S::fringe)
      .def("cell_positions", &S::cell_positions)
      .def("cell_normals", [](const S& s) {
        RowMatX3 n(s.num_cells(), 3);
        for (int c = 0; c < s.num_cells(); ++c) n.row(c) = s.cell_normal(c).transpose();
        return n;
      })
      .def("cell_rest_positions", [](const S& s) {
        RowMatX3 p(s.num_cells(), 3);
        for (int c = 0; c < s.num_cells(); ++c) p.row(c) = s.fire_cells().rest(c).transpose();
        return p;
      })
      .def("cell_speed", [](const S& s, int cell) { return s.cell_speed(checked_cell(s, cell)); }, py::arg("cell"))
      .def("vertex_positions",
           [](const S& s, int threads) {
             // The mesh's FFD is the one parallel loop outside a step: the Simulation's count too.
             py::gil_scoped_release release;
             ScopedThreads scope(threads);
             return s.vertex_positions();
           },
           py::arg("threads"))
      .def("vertex_positions_into",
           [](const S& s, Eigen::Ref<RowMatX3> out, int threads) {
             py::gil_scoped_release release;
             ScopedThreads scope(threads);
             s.vertex_positions_into(out);
           },
           py::arg("out").noconvert(), py::arg("threads"))
      .def("mesh_points",
           [](const S& s, const RowMatXi& idx, const RowMatXd& w, int threads) {
             // Its deform runs in parallel as vertex_positions' does: the Simulation's count.
             py::gil_scoped_release release;
             ScopedThreads scope(threads);
             return s.mesh_points(idx, w);
           },
           py::arg("vertices"), py::arg("weights"), py::arg("threads"))
      .def("mesh_points_redone", [](const S& s) { return s.shell() ? s.shell()->mesh_points_redone() : -1L; })
      .def("vertex_char", &S::vertex_char)
      .def("vertex_ignition_times", &S::vertex_ignition_times)
      .def("vertex_burnout_times", &S::vertex_burnout_times)
      .def("cells_to_vertices",
           [](const S& s, const Eigen::VectorXd& field) {
             if (field.size() != s.num_cells())
               throw std::invalid_argument("field: expected one value per cell (" + std::to_string(s.num_cells()) + ")");
             Eigen::VectorXd out(s.vertices().rows());
             s.fire_cells().cells_to_vertices(field.data(), out.data());
             return out;
           },
           py::arg("field"))
      .def("grad2", [](const S& s, int cell) { return s.grad2(checked_cell(s, cell)); }, py::arg("cell"))
      .def("local_speed",
           [](const S& s, int cell) {
             const LocalSpeed l = s.local_speed(checked_cell(s, cell));
             return py::make_tuple(l.v, l.e_row, l.e_col);
           },
           py::arg("cell"))
      .def("front_active", &S::front_active)
      .def("num_burning", &S::num_burning)
      .def_property_readonly("has_shell", &S::has_shell)
      .def_property_readonly("lattice_size", &S::lattice_size)
      .def_property_readonly("lattice_couples", &S::lattice_couples)
      .def_property_readonly("lattice_thickness", &S::lattice_thickness)
      .def_property_readonly("lattice_fit", &S::lattice_fit)
      .def_property_readonly("lattice_rigidity", &S::lattice_rigidity)
      .def_property_readonly("bending_share", &S::bending_share)
      .def("lattice_positions", &S::lattice_positions)
      .def("lattice_rest_positions", [](const S& s) { return s.lattice() ? s.lattice()->rest() : RowMatX3(0, 3); })
      .def("lattice_springs", [](const S& s) {
        return s.dynamics() ? s.dynamics()->spring_pairs() : Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor>(0, 2);
      })
      .def("control_masses", &S::control_masses)
      .def("control_strength", [](const S& s) { return s.dynamics() ? s.dynamics()->strength() : Eigen::VectorXd(); })
      .def("lattice_awake", [](const S& s) {
        const std::vector<std::uint8_t> a = s.dynamics() ? s.dynamics()->awake() : std::vector<std::uint8_t>();
        py::array_t<bool> out(a.size());
        std::copy(a.begin(), a.end(), out.mutable_data());
        return out;
      })
      .def("heat", [](const S& s) { return s.bending() ? s.bending()->heat() : Eigen::VectorXd(); })
      .def("pyrolysis", [](const S& s) { return s.bending() ? s.bending()->pyrolysis() : Eigen::VectorXd(); })
      .def("rotation", [](const S& s) {
        Eigen::VectorXd d;
        if (s.bending()) s.bending()->rotation(d);
        return d;
      })
      .def("particles",
           [](const S& s) {
             if (!s.particles()) return py::make_tuple(RowMatX3(0, 3), Eigen::VectorXd(0));
             return py::make_tuple(RowMatX3(s.particles()->positions()), Eigen::VectorXd(s.particles()->temperatures()));
           })
      .def("particle_velocities",
           [](const S& s) { return s.particles() ? RowMatX3(s.particles()->velocities()) : RowMatX3(0, 3); })
      .def("particle_ids",
           [](const S& s) {
             const std::vector<std::uint64_t> none;
             const auto& ids = s.particles() ? s.particles()->ids() : none;
             return py::array_t<std::uint64_t>(static_cast<py::ssize_t>(ids.size()), ids.data());
           })
      .def_property_readonly("particles_dropped", [](const S& s) { return s.particles() ? s.particles()->dropped() : 0; })
      .def("set_dynamics", [](S& s, const py::dict& kw) {
        DynamicsParams p = s.params().dynamics;
        apply_kwargs(p, kw, "dynamics");
        s.set_dynamics_params(p);
      })
      .def("phase_seconds", [](const S& s) {
        const PhaseTimes t = s.phase_times();
        py::dict d;
        for (std::size_t p = 0; p < kPhases; ++p) d[phase_name(static_cast<Phase>(p))] = t.seconds[p];
        return d;
      })
      .def("step_stats", [](const S& s) {
        const StepStats& t = s.last_step_stats();
        return py::dict(py::arg("substeps") = t.substeps, py::arg("awake") = t.awake,
                        py::arg("cg_iterations") = t.cg_iterations, py::arg("omega_max") = t.omega_max,
                        py::arg("passes") = t.passes, py::arg("factorizations") = t.factorizations,
                        py::arg("ldlt_solves") = t.ldlt_solves,
                        py::arg("max_strain") = t.max_strain, py::arg("stretch_redos") = t.stretch_redos,
                        py::arg("strain_limited") = t.strain_limited,
                        py::arg("sample_contacts") = t.sample_contacts,
                        py::arg("substeps_by") = substep_cause_name(t.substeps_by));
      })
      .def("frame", [](const S& s) {
        const SheetFrame& f = s.sheet().frame();
        return py::make_tuple(f.origin, f.u, f.v, f.n);
      });
}

}  // namespace thinburn::bind
