// Thin binding of ControlSurface (the lattice of a curved shell) and its embedding;
// python/thinburn/control_surface.py checks the arguments and names them.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "control_surface.hpp"

namespace py = pybind11;

namespace thinburn::bind {
namespace {

// (n, kStencil) views of an embedding's per-slot arrays.
template <class T>
py::array_t<T> slots(const std::vector<T>& v, Eigen::Index n) {
  py::array_t<T> out({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(SurfaceEmbedding::kStencil)});
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

}  // namespace

void define_control_surface(py::module_& m) {
  py::class_<SurfaceEmbedding>(m, "SurfaceEmbedding", "Points embedded in a control surface's lattice.")
      .def_property_readonly("couple", [](const SurfaceEmbedding& e) { return slots(e.couple, e.size()); })
      .def_property_readonly("weight", [](const SurfaceEmbedding& e) { return slots(e.weight, e.size()); })
      .def_property_readonly("share", [](const SurfaceEmbedding& e) { return slots(e.share, e.size()); })
      .def_readonly("rest", &SurfaceEmbedding::rest)
      .def_readonly("rest_normal", &SurfaceEmbedding::rest_normal)
      .def_readonly("offset", &SurfaceEmbedding::offset)
      .def("__len__", [](const SurfaceEmbedding& e) { return e.size(); });

  py::class_<ControlSurface>(m, "ControlSurface", "Couples on a coarse surface fitted to a shell.")
      .def(py::init([](const SurfVerts& v, const SurfFaces& f, double spacing, double thickness, double crease_angle) {
             py::gil_scoped_release release;
             return new ControlSurface(v, f, spacing, thickness, crease_angle);
           }),
           py::arg("vertices"), py::arg("faces"), py::arg("spacing"), py::arg("thickness"),
           py::arg("crease_angle") = kDefaultCreaseAngle)
      .def_property_readonly("couples", &ControlSurface::couples)
      .def_property_readonly("spacing", &ControlSurface::spacing)
      .def_property_readonly("thickness", &ControlSurface::thickness)
      .def_property_readonly("rest", [](const ControlSurface& c) { return c.rest(); })
      .def_property_readonly("springs", [](const ControlSurface& c) {
        const LatticeTopology& t = c.topology();
        Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> s(t.springs(), 3);
        for (int i = 0; i < t.springs(); ++i) s.row(i) << t.spring_a[i], t.spring_b[i], t.kind[i];
        return s;
      })
      .def_property_readonly("nbr_offset", [](const ControlSurface& c) { return c.topology().nbr_offset; })
      .def_property_readonly("nbr_index", [](const ControlSurface& c) { return c.topology().nbr_index; })
      .def("shape_operators",
           [](const ControlSurface& c) {
             const std::vector<Eigen::Matrix3d> S = shape_operators(c.rest(), c.topology());
             py::array_t<double> out({static_cast<py::ssize_t>(S.size()), py::ssize_t(3), py::ssize_t(3)});
             auto o = out.mutable_unchecked<3>();
             for (std::size_t k = 0; k < S.size(); ++k)
               for (int i = 0; i < 3; ++i)
                 for (int j = 0; j < 3; ++j) o(k, i, j) = S[k](i, j);
             return out;
           },
           "Per couple, the rest shape operator (3 x 3, in its tangent plane) fitted to how the "
           "couples' axes turn towards their neighbours: I/R on a sphere of radius R.")
      .def("edge_curvature", &ControlSurface::edge_curvature, py::arg("quantile"))
      .def("embed",
           [](const ControlSurface& c, const RowMatX3& points) {
             py::gil_scoped_release release;
             return c.embed(points);
           },
           py::arg("points"))
      .def("deform",
           [](const ControlSurface& c, const SurfaceEmbedding& e, const RowMatX3& control) {
             py::gil_scoped_release release;
             RowMatX3 out;
             c.deform(e, control, out);
             return out;
           },
           py::arg("embedding"), py::arg("control"))
      .def("normals",
           [](const ControlSurface& c, const SurfaceEmbedding& e, const RowMatX3& control) {
             if (control.rows() != c.rest().rows()) throw std::invalid_argument("control: one row per control vertex expected");
             RowMatX3 out(e.size(), 3);
             for (Eigen::Index i = 0; i < e.size(); ++i) out.row(i) = c.normal(e, i, control).transpose();
             return out;
           },
           py::arg("embedding"), py::arg("control"));
}

}  // namespace thinburn::bind
