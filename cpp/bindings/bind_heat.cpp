#include <pybind11/eigen.h>

#include <stdexcept>
#include <string>

#include "bindings.hpp"
#include "heat.hpp"

namespace py = pybind11;

namespace thinburn::bind {
namespace {

KernelSumOptions make_options(int power, double d_min, const std::string& method,
                              double tolerance, double cutoff = 0.0) {
  KernelSumOptions opt;
  opt.cutoff = cutoff;
  opt.power = power;
  opt.d_min = d_min;
  if (method == "direct") {
    opt.method = SumMethod::Direct;
  } else if (method == "fast") {
    opt.method = SumMethod::Fast;
  } else {
    throw std::invalid_argument("method must be 'direct' or 'fast'");
  }
  opt.tolerance = tolerance;
  validate(opt);
  return opt;
}

py::object result(Eigen::VectorXd&& out, Eigen::VectorXd&& bound, bool return_bound) {
  if (!return_bound) return py::cast(std::move(out));
  return py::make_tuple(std::move(out), std::move(bound));
}

}  // namespace

void define_heat(py::module_& m) {
  m.def(
      "kernel_sum",
      [](const RowMatX3& sources, const Eigen::VectorXd& weights, const RowMatX3& targets,
         int power, double d_min, const std::string& method, double tolerance,
         bool return_bound, double cutoff) {
        const KernelSumOptions opt = make_options(power, d_min, method, tolerance, cutoff);
        Eigen::VectorXd out, bound;
        {
          py::gil_scoped_release release;
          kernel_sum(sources, weights, targets, opt, out, &bound);
        }
        return result(std::move(out), std::move(bound), return_bound);
      },
      py::arg("sources"), py::arg("weights"), py::arg("targets"), py::arg("power") = 2,
      py::arg("d_min") = 0.01, py::arg("method") = "fast", py::arg("tolerance") = 0.01,
      py::arg("return_bound") = false, py::arg("cutoff") = 0.0,
      "out(j) = sum_i w(i) / (|targets(j) - sources(i)| + d_min)^power, direct or fast; with "
      "return_bound, also a per-target bound on |out(j) - exact(j)|; with cutoff > 0 the kernel "
      "minus its value at the cutoff, over the sources within it.");

  py::class_<KernelSummer>(m, "KernelSummer",
                           "An octree over weighted sources, built once and evaluated at many "
                           "targets; holds its buffers between calls.")
      .def(py::init<>())
      .def(
          "build",
          [](KernelSummer& s, const RowMatX3& sources, const Eigen::VectorXd& weights) {
            py::gil_scoped_release release;
            s.build(sources, weights);
          },
          py::arg("sources"), py::arg("weights"),
          "Build the tree over sources (n x 3) with weights (n, finite, >= 0).")
      .def(
          "evaluate",
          [](const KernelSummer& s, const RowMatX3& targets, int power, double d_min,
             const std::string& method, double tolerance, bool return_bound) {
            const KernelSumOptions opt = make_options(power, d_min, method, tolerance);
            Eigen::VectorXd out, bound;
            {
              py::gil_scoped_release release;
              s.evaluate(targets, opt, out, &bound);
            }
            return result(std::move(out), std::move(bound), return_bound);
          },
          py::arg("targets"), py::arg("power") = 2, py::arg("d_min") = 0.01,
          py::arg("method") = "fast", py::arg("tolerance") = 0.01,
          py::arg("return_bound") = false,
          "The kernel sum of the built sources at targets (m x 3).")
      .def_property_readonly("size", &KernelSummer::size, "Number of sources in the tree.")
      .def_property_readonly("node_count", &KernelSummer::node_count, "Number of tree nodes.");

  m.def(
      "particle_heat",
      [](const RowMatX3& particles, const Eigen::VectorXd& temperature, const RowMatX3& vertices,
         double ct, double dt, double d_min, const std::string& method, double tolerance,
         bool return_bound) {
        const KernelSumOptions opt = make_options(2, d_min, method, tolerance);
        Eigen::VectorXd out, bound;
        {
          py::gil_scoped_release release;
          particle_heat(particles, temperature, vertices, ct, dt, opt, out, &bound);
        }
        return result(std::move(out), std::move(bound), return_bound);
      },
      py::arg("particles"), py::arg("temperature"), py::arg("vertices"), py::arg("ct"),
      py::arg("dt"), py::arg("d_min") = 0.01, py::arg("method") = "fast",
      py::arg("tolerance") = 0.01, py::arg("return_bound") = false,
      "Heat received in one step by each vertex from particles, eq (2): "
      "Ct * dt / (4 pi) * sum_A T_A / (d_AB + d_min)^2.");

  m.def(
      "pyrolysis",
      [](const RowMatX3& points, const RowMatX3& vertices, double cp, double d_min,
         const std::string& method, double tolerance, bool return_bound, double cutoff) {
        const KernelSumOptions opt = make_options(1, d_min, method, tolerance, cutoff);
        Eigen::VectorXd out, bound;
        {
          py::gil_scoped_release release;
          pyrolysis(points, vertices, cp, opt, out, &bound);
        }
        return result(std::move(out), std::move(bound), return_bound);
      },
      py::arg("ignition_points"), py::arg("vertices"), py::arg("cp"), py::arg("d_min") = 0.01,
      py::arg("method") = "fast", py::arg("tolerance") = 0.01, py::arg("return_bound") = false,
      py::arg("cutoff") = 0.0,
      "Pyrolysis of each vertex from ignition points, eq (3): Cp * sum_i 1 / (dis_ij + d_min); "
      "with cutoff > 0, over the points within it, minus 1 / (cutoff + d_min) each.");
}
}  // namespace thinburn::bind
