#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>

#include "bindings.hpp"
#include "convert.hpp"
#include "kwargs.hpp"
#include "block_ldlt.hpp"
#include "crumple.hpp"
#include "dynamics.hpp"

namespace py = pybind11;
using namespace pybind11::literals;

namespace thinburn::bind {
namespace {

// explicit_stability_limit's integrator, taken as the integrator keyword is.
Integrator parse_integrator(const py::handle& h) {
  DynamicsParams p;
  set_field(*param::find_field(DynamicsParams::fields(), "integrator"), p, h);
  return p.integrator;
}

std::vector<std::uint8_t> as_flags(const py::array_t<std::uint8_t, py::array::forcecast>& a) {
  if (a.ndim() != 1) throw std::invalid_argument("pinned must be a 1-d array");
  return std::vector<std::uint8_t>(a.data(), a.data() + a.size());
}

Eigen::Vector3d as_vec3(const std::vector<double>& w, const char* name) {
  if (w.size() != 3) throw std::invalid_argument(std::string(name) + " must have 3 components");
  return Eigen::Vector3d(w[0], w[1], w[2]);
}

}  // namespace

void define_dynamics(py::module_& m) {
  py::enum_<Preconditioner>(m, "Preconditioner", "Preconditioner of the implicit integrator's conjugate gradients.")
      .value("Auto", Preconditioner::Auto)
      .value("Ldlt", Preconditioner::Ldlt)
      .value("Jacobi", Preconditioner::Jacobi);
  py::enum_<Integrator>(m, "Integrator", "Time integrator of the lattice.")
      .value("Explicit", Integrator::Explicit, "The paper's eqs 13-15.")
      .value("Symplectic", Integrator::Symplectic, "Symplectic Euler.")
      .value("Implicit", Integrator::Implicit, "Backward Euler (first order), a linear solve per substep.")
      .value("Bdf2", Integrator::Bdf2, "BDF2 (second order), a linear solve per substep.");

  py::class_<StepStats>(m, "StepStats", "What one step did.")
      .def_readonly("substeps", &StepStats::substeps)
      .def_readonly("awake", &StepStats::awake, "Vertices integrated.")
      .def_readonly("cg_iterations", &StepStats::cg_iterations)
      .def_readonly("factorizations", &StepStats::factorizations, "Block LDL^T factorizations (Ldlt preconditioner).")
      .def_readonly("ldlt_solves", &StepStats::ldlt_solves, "Linear solves the LDL^T factor preconditioned (the rest: Jacobi).")
      .def_readonly("omega_max", &StepStats::omega_max, "rad/s, bound on the largest frequency.")
      .def_readonly("max_strain", &StepStats::max_strain, "Largest |l/L - 1| of an awake vertex's springs at the end.")
      .def_readonly("stretch_redos", &StepStats::stretch_redos, "Integrations redone with more substeps for an overstretched spring.")
      .def_readonly("strain_limited", &StepStats::strain_limited, "Couple pairs put back on the strain limit, all substeps and passes.")
      .def_readonly("sample_contacts", &StepStats::sample_contacts, "Shell samples the colliders pushed out, all substeps and passes.")
      .def_readonly("passes", &StepStats::passes)
      .def_property_readonly("substeps_by", [](const StepStats& s) { return substep_cause_name(s.substeps_by); },
                             "What set the substeps: none, set, one, stability, accuracy, contact, stretch_redo.")
      .def("__repr__", [](const StepStats& s) {
        return "StepStats(substeps=" + std::to_string(s.substeps) + " by " + substep_cause_name(s.substeps_by) + ", awake=" +
               std::to_string(s.awake) + ", cg_iterations=" + std::to_string(s.cg_iterations) +
               ", omega_max=" + std::to_string(s.omega_max) + ", passes=" +
               std::to_string(s.passes) + ")";
      });

  py::class_<LatticeDynamics>(m, "LatticeDynamics",
                              "Springs, forces and integration of an FfdLattice's control "
                              "vertices (Liu et al. 2009 §4.3). Keyword arguments are the "
                              "DynamicsParams fields (see docs/dynamics.md).")
      .def(py::init([](FfdLattice& lattice, const py::kwargs& kw) {
             DynamicsParams p;
             apply_kwargs(p, kw, "dynamics");
             return new LatticeDynamics(lattice, p);
           }),
           "lattice"_a, py::keep_alive<1, 2>())
      .def(
          "set_params",
          [](LatticeDynamics& self, const py::kwargs& kw) {
            DynamicsParams p = self.params();
            apply_kwargs(p, kw, "dynamics");
            self.set_params(p);
          },
          "Change the named parameters; the others keep their values.")
      .def_property_readonly("params", [](const LatticeDynamics& s) { return params_dict(s.params()); })
      .def("set_masses", &LatticeDynamics::set_masses, "masses"_a,
           "kg per control vertex (> 0); vertices whose mass changed wake.")
      .def("set_strength", &LatticeDynamics::set_strength, "strength"_a,
           "Per control vertex, in [0, 1]: the share of its springs' stiffness kept (a spring takes "
           "the mean of its ends); changed vertices wake.")
      .def_property_readonly("strength", &LatticeDynamics::strength, "Per control vertex: the stiffness share kept.")
      .def("set_areas", &LatticeDynamics::set_areas, "areas"_a,
           "m^2 of sheet mapped to each control vertex (>= 0), for the wind pressure.")
      .def(
          "set_pinned",
          [](LatticeDynamics& s, const py::array_t<std::uint8_t, py::array::forcecast>& a) {
            s.set_pinned(as_flags(a));
          },
          "pinned"_a, "Per control vertex; pinned ones never move.")
      .def(
          "set_wind", [](LatticeDynamics& s, const std::vector<double>& w) { s.set_wind(as_vec3(w, "wind")); },
          "wind"_a, "Wind velocity, m/s.")
      .def("set_state", &LatticeDynamics::set_state, "positions"_a, "velocities"_a,
           "Set positions and velocities ((2 M^2) x 3 each); everything wakes.")
      .def(
          "step",
          [](LatticeDynamics& s, double dt, const Eigen::VectorXd& D, const Eigen::VectorXd& heat) {
            py::gil_scoped_release release;
            return s.step(dt, D, heat);
          },
          "dt"_a, "D"_a, "heat"_a,
          "Advance by dt (s). D: per couple (M^2) total rotation so far (rad); its increase since "
          "the previous step becomes the crumple. heat: per control vertex, drives buoyancy. "
          "Raises RuntimeError if an explicit integrator needs more than max_substeps.")
      .def_property_readonly("velocities", [](const LatticeDynamics& s) { return RowMatX3(s.velocities()); })
      .def_property_readonly("awake", [](const LatticeDynamics& s) {
        const auto a = s.awake();
        py::array_t<bool> out(a.size());
        for (std::size_t i = 0; i < a.size(); ++i) out.mutable_data()[i] = a[i] != 0;
        return out;
      }, "Per vertex: awake (integrated by the next step) or asleep.")
      .def("forces", &LatticeDynamics::forces,
           "Total force per vertex at the current state (the crumple is a prescribed motion, not in it).")
      .def(
          "stiffness_matrix",
          [](const LatticeDynamics& s) { return Eigen::MatrixXd(s.stiffness_matrix()); },
          "Exact Jacobian of the spring forces w.r.t. positions, dense (6 M^2) x (6 M^2) (for tests).")
      .def("energy", &LatticeDynamics::energy, "Elastic energy of the springs, J.")
      .def("max_frequency", &LatticeDynamics::max_frequency,
           "Upper bound (block Gershgorin) on the largest frequency of M^-1 K, rad/s.")
      .def_property_readonly("rest_lengths", [](const LatticeDynamics& s) { return s.rest_lengths(); })
      .def_property_readonly("spring_pairs", &LatticeDynamics::spring_pairs)
      .def_property_readonly("spring_kinds", [](const LatticeDynamics& s) {
        const auto& k = s.spring_kinds();
        py::array_t<std::uint8_t> out(k.size());
        std::copy(k.begin(), k.end(), out.mutable_data());
        return out;
      }, "0 structure, 1 shear, 2 flex, 3 thickness (top-bottom), 4 transverse (diagonals), "
         "5 zero-stiffness diagonals carrying the membrane springs' blocks.")
      .def_property_readonly("lattice_rigidity", &LatticeDynamics::lattice_rigidity,
                             "N m: the lattice's own flexural rigidity, h^2/2 (k_structure + k_shear + 4 k_flex) unit.")
      .def_property_readonly("bending_share", &LatticeDynamics::bending_share,
                             "Share of the lattice's own bending its layer springs keep (flexural_rigidity / lattice_rigidity, <= 1).")
      .def_property_readonly("membrane_springs", &LatticeDynamics::membrane_springs,
                             "Membrane springs between couples' centres (0 while bending_share is 1).")
      .def_property_readonly("membrane_corners", &LatticeDynamics::membrane_corners,
                             "Lattice corners whose diagonal stiffens beyond the knee (4 on a grid with membrane springs).");

  m.def(
      "explicit_stability_limit",
      [](const py::handle& integ, const py::handle& omega, const py::handle& c) {
        const Integrator i = parse_integrator(integ);
        const double w = to_double("omega", omega), damping = to_double("c", c);
        if (w < 0.0) throw py::value_error("omega must be >= 0");
        if (damping < 0.0) throw py::value_error("c must be >= 0");
        return explicit_stability_limit(i, w, damping);
      },
      "integrator"_a, "omega"_a, "c"_a = 0.0,
      "Largest stable substep of an explicit integrator on modes up to omega with damping c.");
  m.def(
      "crumple_displacements",
      [](int M, const RowMatX3& pos, const Eigen::VectorXd& delta,
         const py::array_t<std::uint8_t, py::array::forcecast>& pinned) {
        if (M < 2 || pos.rows() != 2 * M * M)
          throw std::invalid_argument("pos must have 2*M*M rows");
        if (delta.size() != M * M) throw std::invalid_argument("delta must have M*M entries");
        auto flags = as_flags(pinned);
        if (int(flags.size()) != 2 * M * M) throw std::invalid_argument("pinned must have 2*M*M entries");
        RowMatX3 out;
        crumple_displacements(M, pos, delta, flags, out);
        return out;
      },
      "M"_a, "positions"_a, "delta"_a, "pinned"_a,
      "Chord displacement of every control vertex for per-couple rotation increments (eqs 7-8).");
  m.def(
      "block_ldlt_solve",
      [](int n, const std::vector<int>& col_start, const std::vector<int>& rows,
         const py::array_t<double, py::array::c_style | py::array::forcecast>& blocks,
         const Eigen::VectorXd& rhs) {
        if (blocks.ndim() != 3 || blocks.shape(0) != py::ssize_t(rows.size()) || blocks.shape(1) != 3 ||
            blocks.shape(2) != 3)
          throw std::invalid_argument("blocks must have shape (len(rows), 3, 3)");
        if (rhs.size() != 3 * py::ssize_t(n)) throw std::invalid_argument("rhs must have 3*n entries");
        if (!rhs.allFinite()) throw std::invalid_argument("rhs must be finite");
        // Column-major blocks, as BlockLdlt reads them.
        std::vector<double> values(9 * rows.size());
        auto b = blocks.unchecked<3>();
        for (py::ssize_t q = 0; q < b.shape(0); ++q)
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
              if (!std::isfinite(b(q, r, c))) throw std::invalid_argument("blocks must be finite");
              values[9 * q + 3 * c + r] = b(q, r, c);
            }
        Eigen::VectorXd x = rhs;
        int fill = 0;
        {
          py::gil_scoped_release release;
          BlockLdlt f;
          f.analyze(n, col_start, rows);
          if (!f.factorize(values.data())) throw std::invalid_argument("the matrix is not positive definite");
          f.solve(x.data());
          fill = f.off_diagonal_blocks();
        }
        return py::make_tuple(x, fill);
      },
      "n"_a, "col_start"_a, "rows"_a, "blocks"_a, "rhs"_a,
      "Solve A x = rhs by the block LDL^T of the implicit solve's preconditioner. A is symmetric,\n"
      "of n x n blocks of 3x3, given by its lower triangle: column j's blocks have rows\n"
      "rows[col_start[j]:col_start[j+1]] (>= j; list the diagonal). Returns (x, off-diagonal\n"
      "blocks of L, the fill-in included).");
}

}  // namespace thinburn::bind
