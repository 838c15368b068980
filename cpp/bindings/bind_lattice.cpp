#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <limits>
#include <string>

#include "bindings.hpp"
#include "lattice.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace thinburn::bind {
namespace {

LatticeInterp parse_interp(const std::string& s) {
  if (s == "trilinear") return LatticeInterp::Trilinear;
  if (s == "bspline" || s == "quadratic_bspline") return LatticeInterp::QuadraticBSpline;
  throw std::invalid_argument("interp must be 'trilinear' or 'bspline', got '" + s + "'");
}

py::array_t<std::int32_t> couples_of(const Embedding& e) {
  py::array_t<std::int32_t> out({e.size(), Eigen::Index(e.stencil)});
  std::copy(e.couple.begin(), e.couple.end(), out.mutable_data());
  return out;
}

py::array_t<double> weights_of(const Embedding& e) {
  py::array_t<double> out({e.size(), Eigen::Index(e.stencil)});
  std::copy(e.weight.begin(), e.weight.end(), out.mutable_data());
  return out;
}

}  // namespace

void define_lattice(py::module_& m) {
  py::class_<Embedding>(m, "Embedding",
                        "Points embedded in a lattice: per point a stencil of couples with in-plane "
                        "weights, the weight of the top layer and the rest positions.")
      .def_readonly("stencil", &Embedding::stencil, "Couples per point: 4 (trilinear) or 9 (B-spline).")
      .def_property_readonly("couples", &couples_of, "n x stencil couple indices (i * M + j).")
      .def_property_readonly("weights", &weights_of, "n x stencil in-plane weights (rows sum to 1).")
      .def_readonly("r", &Embedding::r, "Per point: weight of the top vertex of each couple.")
      .def_readonly("rest", &Embedding::rest, "n x 3: rest positions of the points.")
      .def("__len__", &Embedding::size);

  py::class_<FfdLattice>(m, "FfdLattice",
                         "An M x M lattice of couples (Liu et al. 2009 §4.1): rest and current "
                         "positions of its 2 M^2 control vertices, index ((i*M)+j)*2+k.")
      .def(py::init<int, const RowMatX3&>(), "M"_a, "rest"_a,
           "rest: (2 M^2) x 3 rest positions of the control vertices (M >= 2, finite).")
      .def(
          "embed",
          [](const FfdLattice& self, const RowMatX3& params, const RowMatX3& rest_points,
             const std::string& interp) {
            const LatticeInterp li = parse_interp(interp);
            py::gil_scoped_release release;
            return self.embed(params, rest_points, li);
          },
          "params"_a, "rest_points"_a, "interp"_a = "trilinear",
          "Embed points: params n x 3 lattice coordinates (s in [0, M-1] along rows, t in "
          "[0, M-1] along columns, r in [0, 1] bottom -> top), rest_points their rest positions; "
          "interp 'trilinear' or 'bspline' (uniform quadratic B-spline in the plane).")
      .def(
          "deform",
          [](const FfdLattice& self, const Embedding& e) {
            RowMatX3 out(e.size(), 3);
            py::gil_scoped_release release;
            self.deform(e, out);
            return out;
          },
          "embedding"_a,
          "Deformed positions (n x 3) of embedded points: rest point plus the interpolated "
          "displacement of the control vertices.")
      .def(
          "deform_into",
          [](const FfdLattice& self, const Embedding& e, Eigen::Ref<RowMatX3> out) {
            py::gil_scoped_release release;
            self.deform(e, out);
          },
          "embedding"_a, "out"_a.noconvert(),
          "Deform into a preallocated C-contiguous float64 array of shape (n, 3).")
      .def(
          "scatter",
          [](const FfdLattice& self, const Embedding& e, const Eigen::VectorXd& values) {
            return self.scatter(e, values);
          },
          "embedding"_a, "values"_a,
          "Spread per-point values onto the control vertices with the embedding's weights (the "
          "transpose of the interpolation).")
      .def_property(
          "positions", [](const FfdLattice& self) { return RowMatX3(self.positions()); },
          [](FfdLattice& self, const py::object& obj) {
            using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
            py::array raw = py::array::ensure(obj);  // as it is: its dtype decides
            const char kind = raw ? raw.dtype().kind() : 'O';
            const bool real = kind == 'f' || kind == 'i' || kind == 'u';
            if (!raw) PyErr_Clear();
            Array a = real ? Array::ensure(raw) : Array();
            if (!real || !a) {
              PyErr_Clear();
              throw py::type_error("positions must be an array of real numbers, shape (" +
                                   std::to_string(self.size()) + ", 3)");
            }
            if (a.ndim() != 2 || a.shape(0) != self.size() || a.shape(1) != 3)
              throw py::value_error("positions must have shape (" + std::to_string(self.size()) + ", 3)");
            const RowMatX3 x = Eigen::Map<const RowMatX3>(a.data(), a.shape(0), 3);
            if (!x.allFinite()) throw py::value_error("positions must be finite");
            self.positions() = x;
          },
          "Current control positions ((2 M^2) x 3), a copy; assign to set. A LatticeDynamics "
          "built on this lattice does not notice a direct assignment: use its set_state.")
      .def_property_readonly("rest", [](const FfdLattice& self) { return RowMatX3(self.rest()); },
                             "Rest control positions ((2 M^2) x 3).")
      .def_property_readonly("M", &FfdLattice::M, "Couples per side.")
      .def_property_readonly("size", &FfdLattice::size, "Number of control vertices, 2 M^2.")
      .def(
          "index",
          [](const FfdLattice& self, int i, int j, int k) {
            const int M = self.M();
            if (i < 0 || i >= M) throw py::value_error("i must be in [0, M) = [0, " + std::to_string(M) + ")");
            if (j < 0 || j >= M) throw py::value_error("j must be in [0, M) = [0, " + std::to_string(M) + ")");
            if (k != 0 && k != 1) throw py::value_error("k must be 0 (bottom) or 1 (top)");
            return self.index(i, j, k);
          },
          "i"_a, "j"_a, "k"_a, "Index of control vertex (i, j, k).");

  // The Shell's mesh cache on its own, for tests of its tolerance on lattices moved by hand.
  py::class_<CachedDeform>(m, "CachedDeform",
                           "An embedding's deformed points kept from call to call: a call redoes "
                           "those whose couples drifted by more than tolerance (m) since their "
                           "last redo (0: bitwise, the result is FfdLattice.deform's).")
      .def(py::init<const Embedding&, int, double>(), "embedding"_a, "couples"_a, "tolerance"_a = 0.0)
      .def(
          "deform",
          [](CachedDeform& self, const FfdLattice& lattice, const Embedding& e, double z_min) {
            RowMatX3 out(e.size(), 3);
            py::gil_scoped_release release;
            self.deform_into(lattice, e, z_min, out);
            return out;
          },
          "lattice"_a, "embedding"_a, "z_min"_a = -std::numeric_limits<double>::infinity(),
          "The points (n x 3) deformed by the lattice's positions now; z_min a floor.")
      .def_property_readonly("points_redone", &CachedDeform::points_redone,
                             "Points the last call computed.")
      .def_property_readonly("tolerance", &CachedDeform::tolerance, "m.");
}

}  // namespace thinburn::bind
