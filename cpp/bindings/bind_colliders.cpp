// Collision objects (cpp/colliders.hpp); python/thinburn/colliders.py wraps them.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <memory>

#include "bindings.hpp"
#include "colliders.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace thinburn::bind {

void define_colliders(py::module_& m) {
  using C = Colliders;
  py::class_<C, std::shared_ptr<C>>(m, "Colliders",
                                    "Spheres, oriented boxes and closed meshes: signed distance and outward normal.")
      .def(py::init<>())
      .def("add_sphere", &C::add_sphere, py::arg("centre"), py::arg("radius"), py::arg("friction"),
           py::arg("thickness"))
      .def("add_box", &C::add_box, py::arg("centre"), py::arg("half_extents"), py::arg("rotation"),
           py::arg("friction"), py::arg("thickness"))
      .def("add_mesh", &C::add_mesh, py::arg("vertices"), py::arg("faces"), py::arg("friction"),
           py::arg("thickness"), py::arg("resolution"), py::call_guard<py::gil_scoped_release>())
      .def("set_transform", &C::set_transform, py::arg("index"), py::arg("translation"), py::arg("rotation"))
      .def("set_friction", &C::set_friction, py::arg("index"), py::arg("friction"))
      .def("__len__", &C::size)
      .def_property_readonly("version", &C::version)
      .def("grid_spacing", &C::grid_spacing, py::arg("index"))
      .def("kind", &C::kind, py::arg("index"))
      .def(
          "query",
          [](const C& c, const Colliders::RowMatX3& p) {
            Eigen::VectorXd d(p.rows());
            Colliders::RowMatX3 n(p.rows(), 3);
            Eigen::VectorXi idx(p.rows());
            {
              py::gil_scoped_release release;
              for (Eigen::Index r = 0; r < p.rows(); ++r) {
                const ColliderHit h = c.query(p.row(r).transpose());
                d(r) = h.distance;
                n.row(r) = h.normal.transpose();
                idx(r) = h.index;
              }
            }
            return py::make_tuple(d, n, idx);
          },
          py::arg("points"), "(distance, normal, index) of the nearest collider at each point.");
}

}  // namespace thinburn::bind
