// Thin binding of the Simulation; validation lives in python/thinburn/simulation.py.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <stdexcept>
#include <string>

#include "bindings.hpp"
#include "simulation.hpp"

namespace py = pybind11;

namespace thinburn::bind {
namespace {

FrontMethod front_from_name(const std::string& name) {
  if (name == "cellular") return FrontMethod::Cellular8;
  if (name == "cellular16") return FrontMethod::Cellular16;
  if (name == "fmm1") return FrontMethod::Fmm1;
  if (name == "fmm") return FrontMethod::Fmm2;
  throw std::invalid_argument("front: unknown method '" + name + "'");
}

std::string front_name(FrontMethod m) {
  switch (m) {
    case FrontMethod::Cellular8: return "cellular";
    case FrontMethod::Cellular16: return "cellular16";
    case FrontMethod::Fmm1: return "fmm1";
    case FrontMethod::Fmm2: return "fmm";
  }
  return "fmm";
}

template <class T>
py::array_t<T> grid(const std::vector<T>& v, int n) {
  py::array_t<T> a({n, n});
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

void define_params(py::module_& m) {
  py::class_<SimulationParams> p(m, "SimulationParams", "Every scalar of a simulation (SI units).");
  p.def(py::init<>())
      .def_readwrite("cells", &SimulationParams::cells)
      .def_property("front", [](const SimulationParams& s) { return front_name(s.front); },
                    [](SimulationParams& s, const std::string& n) { s.front = front_from_name(n); })
      .def_readwrite("seed", &SimulationParams::seed)
      .def_readwrite("v0", &SimulationParams::v0)
      .def_readwrite("cv", &SimulationParams::cv)
      .def_readwrite("v_floor", &SimulationParams::v_floor)
      .def_readwrite("speed_noise", &SimulationParams::speed_noise)
      .def_readwrite("burn_duration", &SimulationParams::burn_duration)
      .def_readwrite("duration_noise", &SimulationParams::duration_noise)
      .def_readwrite("climb", &SimulationParams::climb)
      .def_readwrite("wind_spread", &SimulationParams::wind_spread)
      .def_readwrite("max_drive", &SimulationParams::max_drive)
      .def_readwrite("areal_density", &SimulationParams::areal_density)
      .def_readwrite("ash_fraction", &SimulationParams::ash_fraction);
}

}  // namespace

void define_simulation(py::module_& m) {
  define_params(m);
  using S = Simulation;
  py::class_<S>(m, "Simulation", "The burning sheet, stepped in time.")
      .def(py::init([](const RowMatX3& v, const RowMatX3i& f, const RowMatX2& uv, const SimulationParams& p) {
             py::gil_scoped_release release;
             return new S(v, f, uv, p);
           }),
           py::arg("vertices"), py::arg("faces"), py::arg("uv"), py::arg("params"))
      .def("ignite", &S::ignite, py::arg("point"), py::arg("time"), py::arg("radius"),
           py::call_guard<py::gil_scoped_release>())
      .def("step", &S::step, py::arg("dt"), py::call_guard<py::gil_scoped_release>())
      .def_property_readonly("time", &S::time)
      .def_property("wind", &S::wind, &S::set_wind)
      .def_property_readonly("cells", [](const S& s) { return s.sheet().cells(); })
      .def_property_readonly("cell_size", [](const S& s) { return py::make_tuple(s.sheet().dv(), s.sheet().du()); })
      .def_property_readonly("area", [](const S& s) { return s.sheet().area(); })
      .def("inside", [](const S& s) { return grid(s.sheet().inside(), s.sheet().cells()); })
      .def("cell_states", [](const S& s) { return grid(s.cell_states(), s.sheet().cells()); })
      .def("ignition_times", [](const S& s) { return grid(s.ignition_times(), s.sheet().cells()); })
      .def("burn_durations", [](const S& s) { return grid(s.burn_durations(), s.sheet().cells()); })
      .def("cell_char", [](const S& s) { return grid(s.cell_char(), s.sheet().cells()); })
      .def("cell_mass", [](const S& s) { return grid(s.cell_mass(), s.sheet().cells()); })
      .def("fringe", &S::fringe)
      .def("cell_positions", &S::cell_positions)
      .def("cell_rest_positions", [](const S& s) { return s.sheet().cell_rest(); })
      .def("vertex_positions", &S::vertex_positions)
      .def("vertex_char", &S::vertex_char)
      .def("vertex_ignition_times", &S::vertex_ignition_times)
      .def("vertex_burnout_times", &S::vertex_burnout_times)
      .def("cells_to_vertices",
           [](const S& s, const Eigen::VectorXd& field) {
             if (field.size() != s.sheet().num_cells()) throw std::invalid_argument("field: expected N*N values");
             Eigen::VectorXd out(s.sheet().vertices().rows());
             s.sheet().cells_to_vertices(field.data(), out.data());
             return out;
           },
           py::arg("field"))
      .def("grad2", &S::grad2, py::arg("cell"))
      .def("local_speed",
           [](const S& s, int cell) {
             const LocalSpeed l = s.local_speed(cell);
             return py::make_tuple(l.v, l.e_row, l.e_col);
           },
           py::arg("cell"))
      .def("front_active", &S::front_active)
      .def("num_burning", &S::num_burning)
      .def("frame", [](const S& s) {
        const SheetFrame& f = s.sheet().frame();
        return py::make_tuple(f.origin, f.u, f.v, f.n);
      });
}

}  // namespace thinburn::bind
