#include "bending.hpp"

#include <cmath>
#include <stdexcept>

namespace thinburn {

const std::vector<param::Field<BendingParams>>& BendingParams::fields() {
  using P = BendingParams;
  using namespace param;
  static const std::vector<Field<P>> table = {
      field("ct", &P::ct, at_least(0), "eq 2: heat units per (K s / m^2)"),
      field("cp", &P::cp, at_least(0), "eq 3 (Table 1 Cp): pyrolysis per metre^-1"),
      field("alpha", &P::alpha, "eq 6: radians per unit heat difference"),
      field("beta", &P::beta, "eq 6: radians per unit pyrolysis difference"),
      field("d_min", &P::d_min, above(0), "m: guards d -> 0 in eqs 2 and 3"),
      field("pyrolysis_range", &P::pyrolysis_range, at_least(0),
            "m: eq 3 counts the ignition points within this distance (0: all)"),
      field("max_rotation", &P::max_rotation, at_least(0), "rad: |D| saturates smoothly here"),
      // The keywords name the kernel sums' options after what they sum.
      field("heat_tolerance", &P::tolerance, within(0, 1, true, true),
            "relative error bound of the fast kernel sums"),
      field("heat_fast", &P::fast, "octree sums (false: the direct all-pairs reference)"),
  };
  return table;
}

void validate(const BendingParams& p) { param::check_all(BendingParams::fields(), p); }

Bending::Bending(int couples, const BendingParams& p) : p_(p), couples_(couples) {
  if (couples < 1) throw std::invalid_argument("couples must be >= 1");
  validate(p);
  const int n = 2 * couples;
  heat_ = rate_ = pyro_ = step_heat_ = Eigen::VectorXd::Zero(n);
}

KernelSumOptions Bending::options(int power) const {
  KernelSumOptions o;
  o.power = power;
  o.d_min = p_.d_min;
  o.method = p_.fast ? SumMethod::Fast : SumMethod::Direct;
  o.tolerance = p_.tolerance;
  if (power == 1) o.cutoff = p_.pyrolysis_range;
  return o;
}

void Bending::add_particle_heat(const RowMatX3& control, const RowMatX3& particles,
                                const Eigen::VectorXd& temperature, double dt) {
  if (particles.rows() == 0) {
    rate_.setZero();
    return;
  }
  particle_heat(particles, temperature, control, p_.ct, dt, options(2), step_heat_);
  heat_ += step_heat_;
  rate_ = step_heat_ / dt;
}

void Bending::set_pyrolysis(const RowMatX3& control, const RowMatX3& ignition_points) {
  if (ignition_points.rows() == 0) {
    pyro_.setZero();
    return;
  }
  thinburn::pyrolysis(ignition_points, control, p_.cp, options(1), pyro_);
}

void Bending::rotation(Eigen::VectorXd& out) const {
  out.resize(couples_);
  const double dmax = p_.max_rotation;
  for (int c = 0; c < couples_; ++c) {
    const double raw = p_.alpha * (heat_[2 * c + 1] - heat_[2 * c]) + p_.beta * (pyro_[2 * c + 1] - pyro_[2 * c]);
    out[c] = dmax > 0 ? dmax * std::tanh(raw / dmax) : raw;
  }
}

}  // namespace thinburn
