#include "bending.hpp"

#include <cmath>
#include <stdexcept>

namespace thinburn {

Bending::Bending(int couples, const BendingParams& p) : p_(p), couples_(couples) {
  if (couples < 1) throw std::invalid_argument("couples must be >= 1");
  if (!(p.d_min > 0)) throw std::invalid_argument("d_min must be > 0");
  const int n = 2 * couples;
  heat_ = rate_ = pyro_ = step_heat_ = Eigen::VectorXd::Zero(n);
}

KernelSumOptions Bending::options(int power) const {
  KernelSumOptions o;
  o.power = power;
  o.d_min = p_.d_min;
  o.method = p_.fast ? SumMethod::Fast : SumMethod::Direct;
  o.tolerance = p_.tolerance;
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
