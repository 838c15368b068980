// Thin bindings of SurfaceCells and SurfaceFront; python/thinburn/surface_front.py checks
// the arguments and names them. Long calls release the GIL.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "surface_cells.hpp"
#include "surface_front.hpp"

namespace py = pybind11;

namespace thinburn::bind {
namespace {

using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Ints = py::array_t<int, py::array::c_style | py::array::forcecast>;

std::vector<Eigen::Vector3d> vec3s(const Doubles& a, const std::string& name) {
  if (a.ndim() != 2 || a.shape(1) != 3) throw py::value_error(name + " must have shape (n, 3)");
  std::vector<Eigen::Vector3d> out(a.shape(0));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) out[i] = {a.at(i, 0), a.at(i, 1), a.at(i, 2)};
  return out;
}

py::array_t<double> rows3(const std::vector<Eigen::Vector3d>& v) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
  auto m = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) m(i, k) = v[i][k];
  return out;
}

template <class T>
py::array_t<T> flat(const std::vector<T>& v) {
  py::array_t<T> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

template <class T>
py::array_t<T> triples(const std::vector<std::array<T, 3>>& v) {
  py::array_t<T> out({static_cast<py::ssize_t>(v.size()), py::ssize_t{3}});
  auto m = out.template mutable_unchecked<2>();
  for (std::size_t i = 0; i < v.size(); ++i)
    for (int k = 0; k < 3; ++k) m(i, k) = v[i][k];
  return out;
}

std::shared_ptr<SurfaceCells> make_cells(const Doubles& vertices, const Ints& faces, int cells,
                                         double spacing, double weld_tol, int lloyd_iters, double refine) {
  if (vertices.ndim() != 2 || vertices.shape(1) != 3) throw py::value_error("vertices must have shape (n, 3)");
  if (faces.ndim() != 2 || faces.shape(1) != 3) throw py::value_error("faces must have shape (m, 3)");
  const Eigen::Map<const SurfVerts> V(vertices.data(), vertices.shape(0), 3);
  const Eigen::Map<const SurfFaces> F(faces.data(), faces.shape(0), 3);
  CellOptions opt;
  opt.cells = cells;
  opt.spacing = spacing;
  opt.weld_tol = weld_tol;
  opt.lloyd_iters = lloyd_iters;
  opt.refine = refine;
  py::gil_scoped_release release;
  return std::make_shared<SurfaceCells>(V, F, opt);
}

// The Python-facing front: a SurfaceFront plus a fixed per-cell speed (and drive), so the
// event loop never calls back into Python and runs without the GIL.
class PySurfaceFront {
 public:
  PySurfaceFront(std::shared_ptr<const SurfaceCells> cells, double init_radius)
      : cells_(cells), front_(cells, SurfaceFrontOptions{init_radius}) {}

  void set_speed(const Doubles& speed, const py::object& drive) {
    const std::size_t n = cells_->size();
    if (static_cast<std::size_t>(speed.size()) != n)
      throw py::value_error("speed must have one entry per cell (" + std::to_string(n) + ")");
    std::vector<double> v(speed.data(), speed.data() + n);
    for (double x : v)
      if (!(std::isfinite(x) && x >= 0.0)) throw py::value_error("speed must be finite and >= 0");
    std::vector<Eigen::Vector3d> e;
    if (!drive.is_none()) {
      e = vec3s(drive.cast<Doubles>(), "drive");
      if (e.size() != n) throw py::value_error("drive must have shape (cells, 3)");
      for (const auto& x : e)
        if (!(x.allFinite() && x.squaredNorm() < 1.0)) throw py::value_error("drive must be finite with |e| < 1");
    }
    v_ = std::move(v);
    e_ = std::move(e);
  }

  void ignite_point(const Eigen::Vector3d& p, double t0) {
    require_speed();
    front_.ignite_point(p, t0, fn());
  }
  void ignite_cell(int cell, double t0) {
    require_speed();
    front_.ignite_cell(cell, t0, fn());
  }
  py::array_t<int> advance(double t_end) {
    require_speed();
    const std::vector<int>* out = nullptr;
    {
      py::gil_scoped_release release;
      out = &front_.advance(t_end, fn());
    }
    return flat(*out);
  }
  py::array_t<double> arrival() const { return flat(front_.arrival()); }
  bool accepted(int cell) const { return front_.accepted(cell); }
  std::size_t num_trial() const { return front_.num_trial(); }
  double time() const { return front_.time(); }
  std::shared_ptr<const SurfaceCells> cells() const { return cells_; }
  py::tuple virtual_sources() const {
    return py::make_tuple(flat(front_.source_times()), rows3(front_.source_vectors()), flat(front_.front_curvature()));
  }

 private:
  void require_speed() const {
    if (v_.empty()) throw py::value_error("speed is not set: call set_speed(speed) first");
  }
  SurfaceSpeedFn fn() const {
    if (e_.empty()) return [this](int c) { return SurfaceSpeed{v_[c]}; };
    return [this](int c) { return SurfaceSpeed{v_[c], e_[c]}; };
  }

  std::shared_ptr<const SurfaceCells> cells_;
  SurfaceFront front_;
  std::vector<double> v_;
  std::vector<Eigen::Vector3d> e_;
};

}  // namespace

void define_surface_front(py::module_& m) {
  py::class_<SurfaceCells, std::shared_ptr<SurfaceCells>>(
      m, "SurfaceCells", "Cells of a triangulated surface: a uniform sampling of the surface itself.")
      .def(py::init(&make_cells), py::arg("vertices"), py::arg("faces"), py::arg("cells") = 64,
           py::arg("spacing") = 0.0, py::arg("weld_tol") = 1e-6, py::arg("lloyd_iters") = 3,
           py::arg("refine") = 3.0)
      .def_property_readonly("size", &SurfaceCells::size)
      .def_property_readonly("spacing", &SurfaceCells::spacing)
      .def_property_readonly("total_area", &SurfaceCells::total_area)
      .def_property_readonly("dense_size", &SurfaceCells::dense_size)
      .def_property_readonly("positions", [](const SurfaceCells& c) { return rows3(c.positions()); })
      .def_property_readonly("normals", [](const SurfaceCells& c) { return rows3(c.normals()); })
      .def_property_readonly("gauss_curvature", [](const SurfaceCells& c) { return flat(c.gauss_curvature()); })
      .def_property_readonly("on_boundary", [](const SurfaceCells& c) { return flat(c.on_boundary()); })
      .def_property_readonly("areas", [](const SurfaceCells& c) { return flat(c.areas()); })
      .def_property_readonly("nbr_offset", [](const SurfaceCells& c) { return flat(c.nbr_offset()); })
      .def_property_readonly("nbr_index", [](const SurfaceCells& c) { return flat(c.nbr_index()); })
      .def_property_readonly("triangles", [](const SurfaceCells& c) { return triples(c.triangles()); })
      .def_property_readonly("vertex_cells", [](const SurfaceCells& c) { return triples(c.vertex_cells()); })
      .def_property_readonly("vertex_weights", [](const SurfaceCells& c) { return triples(c.vertex_weights()); })
      .def("nearest", [](const SurfaceCells& c, const Doubles& pts) {
             const std::vector<Eigen::Vector3d> p = vec3s(pts, "points");
             std::vector<int> out(p.size());
             {
               py::gil_scoped_release release;
               for (std::size_t i = 0; i < p.size(); ++i) out[i] = c.nearest(p[i]);
             }
             return flat(out);
           }, py::arg("points"), "Index of the nearest cell for each of (k, 3) points.");

  py::class_<PySurfaceFront>(m, "SurfaceFront", "Incremental fire front on surface cells.")
      .def(py::init<std::shared_ptr<const SurfaceCells>, double>(), py::arg("cells"),
           py::arg("init_radius") = SurfaceFrontOptions().init_radius)
      .def("set_speed", &PySurfaceFront::set_speed, py::arg("speed"), py::arg("drive") = py::none())
      .def("ignite_point", &PySurfaceFront::ignite_point, py::arg("point"), py::arg("t0"),
           py::call_guard<py::gil_scoped_release>())
      .def("ignite_cell", &PySurfaceFront::ignite_cell, py::arg("cell"), py::arg("t0"),
           py::call_guard<py::gil_scoped_release>())
      .def("advance", &PySurfaceFront::advance, py::arg("t_end"))
      .def("arrival", &PySurfaceFront::arrival)
      .def("accepted", &PySurfaceFront::accepted, py::arg("cell"))
      .def("num_trial", &PySurfaceFront::num_trial)
      .def("virtual_sources", &PySurfaceFront::virtual_sources,
           "(source times, source-to-cell vectors (cells, 3)): where each cell's front comes from.")
      .def_property_readonly("time", &PySurfaceFront::time)
      .def_property_readonly("cells", &PySurfaceFront::cells);

  m.def(
      "surface_arrival_times",
      [](std::shared_ptr<const SurfaceCells> cells, const Doubles& speed, const py::object& drive,
         const Doubles& points, const Doubles& t0) {
        std::vector<double> v(speed.data(), speed.data() + speed.size());
        std::vector<Eigen::Vector3d> e;
        if (!drive.is_none()) e = vec3s(drive.cast<Doubles>(), "drive");
        std::vector<Eigen::Vector3d> p = vec3s(points, "sources");
        std::vector<double> t(t0.data(), t0.data() + t0.size());
        std::vector<double> out;
        {
          py::gil_scoped_release release;
          out = surface_arrival_times(cells, v, e, p, t);
        }
        return flat(out);
      },
      py::arg("cells"), py::arg("speed"), py::arg("drive"), py::arg("points"), py::arg("t0"));
}

}  // namespace thinburn::bind
