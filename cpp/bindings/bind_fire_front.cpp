#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "bindings.hpp"
#include "fire_front.hpp"

namespace py = pybind11;

namespace thinburn::bind {
namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// A float64 array of exactly n entries (any shape), copied; anything else is refused.
std::vector<double> doubles(const py::handle& obj, const std::string& name, std::size_t n) {
  if (!py::isinstance<py::array>(obj)) throw py::type_error(name + " must be a numpy float64 array");
  auto arr = py::reinterpret_borrow<py::array>(obj);
  if (arr.dtype().kind() != 'f' || arr.dtype().itemsize() != 8)
    throw py::type_error(name + " must have dtype float64, got " + py::str(arr.dtype()).cast<std::string>());
  if (static_cast<std::size_t>(arr.size()) != n)
    throw py::value_error(name + " must have ny*nx = " + std::to_string(n) + " entries, got " +
                          std::to_string(arr.size()));
  auto c = DoubleArray::ensure(arr);
  return std::vector<double>(c.data(), c.data() + n);
}

py::array_t<double> grid_array(const std::vector<double>& v, int ny, int nx) {
  py::array_t<double> out({static_cast<py::ssize_t>(ny), static_cast<py::ssize_t>(nx)});
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

// The Python-facing front: a FireFront plus a fixed speed field (and optional drive), so the
// event loop never calls back into Python and runs without the GIL.
class PyFireFront {
 public:
  PyFireFront(int ny, int nx, double dy, double dx, FrontMethod method, const FrontOptions& opt)
      : front_(ny, nx, dy, dx, method, opt) {}

  void set_inside(const py::array& inside) {
    const std::size_t n = cells();
    if (inside.dtype().itemsize() != 1 || (inside.dtype().kind() != 'u' && inside.dtype().kind() != 'b'))
      throw py::type_error("inside must have dtype uint8 or bool");
    if (static_cast<std::size_t>(inside.size()) != n)
      throw py::value_error("inside must have ny*nx = " + std::to_string(n) + " entries");
    auto c = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(inside);
    front_.set_inside(std::vector<std::uint8_t>(c.data(), c.data() + n));
  }

  void set_speed(const py::object& speed, const py::object& e_row, const py::object& e_col) {
    const std::size_t n = cells();
    std::vector<double> v = doubles(speed, "speed", n);
    for (double x : v)
      if (!(std::isfinite(x) && x >= 0.0)) throw py::value_error("speed must be finite and >= 0");
    if (e_row.is_none() != e_col.is_none())
      throw py::value_error("e_row and e_col must both be given or both be None");
    std::vector<double> er, ec;
    if (!e_row.is_none()) {
      er = doubles(e_row, "e_row", n);
      ec = doubles(e_col, "e_col", n);
      for (std::size_t i = 0; i < n; ++i)
        if (!(er[i] * er[i] + ec[i] * ec[i] < 1.0))
          throw py::value_error("drive (e_row, e_col) must be finite with |e| < 1");
    }
    v_ = std::move(v);
    er_ = std::move(er);
    ec_ = std::move(ec);
  }

  void ignite(double row, double col, double t0) {
    require_speed();
    py::gil_scoped_release release;
    front_.ignite(FrontSource{row, col, t0}, fn());
  }

  py::array_t<int> advance(double t_end) {
    require_speed();
    const std::vector<int>* cells = nullptr;
    {
      py::gil_scoped_release release;
      cells = &front_.advance(t_end, fn());
    }
    py::array_t<int> out(static_cast<py::ssize_t>(cells->size()));
    std::copy(cells->begin(), cells->end(), out.mutable_data());
    return out;
  }

  py::array_t<double> arrival() const { return grid_array(front_.arrival(), front_.ny(), front_.nx()); }
  bool accepted(int cell) const { return front_.accepted(cell); }
  std::size_t num_trial() const { return front_.num_trial(); }
  int ny() const { return front_.ny(); }
  int nx() const { return front_.nx(); }
  double time() const { return front_.time(); }

 private:
  std::size_t cells() const { return static_cast<std::size_t>(front_.ny()) * front_.nx(); }
  void require_speed() const {
    if (v_.empty()) throw py::value_error("speed is not set: call set_speed(speed) first");
  }
  SpeedFn fn() const {
    if (er_.empty()) return [this](int c) { return LocalSpeed{v_[c]}; };
    return [this](int c) { return LocalSpeed{v_[c], er_[c], ec_[c]}; };
  }

  FireFront front_;
  std::vector<double> v_, er_, ec_;
};

}  // namespace

void define_fire_front(py::module_& m) {
  py::enum_<FrontMethod>(m, "FrontMethod", "How the fire front moves from cell to cell.")
      .value("Cellular8", FrontMethod::Cellular8, "The paper's 8-neighbour rule (Dijkstra).")
      .value("Cellular16", FrontMethod::Cellular16, "The neighbour rule with knight moves.")
      .value("Fmm1", FrontMethod::Fmm1, "First-order fast marching.")
      .value("Fmm2", FrontMethod::Fmm2, "Second-order fast marching, exact near sources.");

  py::class_<PyFireFront>(m, "FireFront",
                          "Incremental fire-front solver on an ny x nx grid (spacings dy, dx in m).\n"
                          "Set the speed field (and drive) with set_speed, ignite point sources,\n"
                          "then advance in time; cells are accepted in arrival order.")
      .def(py::init([](int ny, int nx, double dy, double dx, FrontMethod method,
                       double init_radius, bool factored, bool huygens) {
             FrontOptions opt;
             opt.init_radius = init_radius;
             opt.factored = factored;
             opt.huygens = huygens;
             return PyFireFront(ny, nx, dy, dx, method, opt);
           }),
           py::arg("ny"), py::arg("nx"), py::arg("dy"), py::arg("dx"), py::arg("method"),
           py::arg("init_radius") = FrontOptions().init_radius,
           py::arg("factored") = FrontOptions().factored, py::arg("huygens") = FrontOptions().huygens,
           "init_radius: cells within this distance (in cells) of a source get exact times; "
           "factored: Fmm2 solves for tau in T = t0 + T0 tau; huygens: cells with a drive use "
           "the 8-neighbour Huygens update (else the 4-neighbour Eulerian one).")
      .def("set_inside", &PyFireFront::set_inside, py::arg("inside"),
           "Cells with inside == 0 never burn. uint8/bool array of ny*nx entries.")
      .def("set_speed", &PyFireFront::set_speed, py::arg("speed"), py::arg("e_row") = py::none(),
           py::arg("e_col") = py::none(),
           "Speed field (float64, ny*nx, m/s, >= 0; 0 = cannot burn) and optional drive "
           "components (float64, ny*nx, |e| < 1) used by later ignite/advance calls.")
      .def("ignite", &PyFireFront::ignite, py::arg("row"), py::arg("col"), py::arg("t0"),
           "Ignite a point source at fractional (row, col) at time t0 (>= every t_end so far).")
      .def("advance", &PyFireFront::advance, py::arg("t_end"),
           "Accept every cell with arrival time <= t_end, in time order; returns those cells "
           "(row*nx + col) in acceptance order.")
      .def("arrival", &PyFireFront::arrival, "Accepted arrival times, (ny, nx), +inf where not yet.")
      .def("accepted", &PyFireFront::accepted, py::arg("cell"), "Whether the cell's time is final.")
      .def("num_trial", &PyFireFront::num_trial, "Size of the narrow band.")
      .def_property_readonly("ny", &PyFireFront::ny)
      .def_property_readonly("nx", &PyFireFront::nx)
      .def_property_readonly("time", &PyFireFront::time, "Largest t_end advanced to so far.");

  m.def(
      "arrival_times",
      [](const py::object& speed, int ny, int nx, const py::object& e_row, const py::object& e_col,
         const std::vector<std::array<double, 3>>& sources, double dy, double dx, FrontMethod method) {
        if (ny < 1 || nx < 1) throw py::value_error("speed: the grid must be at least 1 x 1");
        const std::size_t n = static_cast<std::size_t>(ny) * nx;
        std::vector<double> v = doubles(speed, "speed", n), er, ec;
        if (e_row.is_none() != e_col.is_none())
          throw py::value_error("e_row and e_col must both be given or both be None");
        if (!e_row.is_none()) {
          er = doubles(e_row, "e_row", n);
          ec = doubles(e_col, "e_col", n);
        }
        std::vector<FrontSource> src;
        for (const auto& s : sources) src.push_back({s[0], s[1], s[2]});
        std::vector<double> t;
        {
          py::gil_scoped_release release;
          t = arrival_times(ny, nx, v, er, ec, src, dy, dx, method);
        }
        return grid_array(t, ny, nx);
      },
      py::arg("speed"), py::arg("ny"), py::arg("nx"), py::arg("e_row"), py::arg("e_col"),
      py::arg("sources"), py::arg("dy"), py::arg("dx"), py::arg("method"),
      "One-shot arrival times (ny, nx) from point sources [(row, col, t0)], +inf where "
      "unreachable. speed: float64 ny*nx (0 = never burns); e_row/e_col: None or float64 ny*nx.");
}

}  // namespace thinburn::bind
