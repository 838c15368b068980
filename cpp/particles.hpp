#pragma once
/// @brief Fire particles (Reeves 1983), the heat source of Liu et al. 2009 §4.2 eq (2).
///
/// Particles are born at burning fringe cells, carry a temperature (K above ambient) that
/// decays exponentially, rise with a buoyancy proportional to that temperature, relax
/// toward the wind with a linear drag, feel a turbulent velocity fluctuation, and die when
/// they reach a jittered lifetime. See docs/particles.md for the model and its defaults.
#include <Eigen/Core>

#include <cstdint>
#include <vector>

#include "param_table.hpp"

namespace thinburn {

using RowMatX3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// @brief Parameters of the fire particle system (SI units; defaults for paper, flames ~3-10 cm tall).
struct ParticleParams {
  int capacity = 20000;           ///< fixed pool size; births beyond it are dropped and counted
  double birth_rate = 4000.0;     ///< particles per second per metre of fire front
  double temperature0 = 900.0;    ///< K above ambient at birth
  double cooling = 8.0;           ///< 1/s, T = temperature0 * exp(-cooling * age)
  double lifetime = 0.35;         ///< s, mean lifetime
  double lifetime_jitter = 0.3;   ///< lifetime uniform in lifetime * [1 - j, 1 + j], 0 <= j < 1
  double buoyancy = 8.0;          ///< m/s^2 upward at temperature0, proportional to T
  double drag = 8.0;              ///< 1/s, relaxation rate of the velocity toward the wind
  double turbulence = 0.1;        ///< m/s, stationary rms of each velocity component's fluctuation
  double birth_speed = 0.05;      ///< m/s along the emitting side's normal
  double vertical_band = 0.1;     ///< emitters with |n.z| < this emit on both sides, alternating
  std::uint64_t seed = 0;         ///< seed of the counter-based random stream

  /// @brief The table of these fields (param_table.hpp): names, bounds, docs.
  static const std::vector<param::Field<ParticleParams>>& fields();
};

/// @brief A fixed-capacity pool of fire particles, structure of arrays, deterministic.
///
/// Full-pool policy: a birth that finds the pool full is dropped and counted in dropped();
/// live particles are never recycled early. Every birth candidate gets a serial id whether
/// or not it is dropped, and every random number is a hash of (seed, id or emitter, step
/// index), so a surviving particle's history does not depend on the pool size and results
/// are bit-identical for any thread count. The first count() rows/entries are live, in
/// birth order (killing compacts the pool stably).
class ParticleSystem {
 public:
  /// @brief Create an empty pool; throws std::invalid_argument on bad parameters.
  explicit ParticleSystem(const ParticleParams& params);

  /// @brief Emit particles for one step of length dt from k emitters.
  /// @param pos emitter positions (k x 3), m
  /// @param normal sheet normals at the emitters (k x 3), normalised here, must be nonzero
  /// @param length fire-front length per emitter (k), m; expected births birth_rate*length*dt
  /// @param dt step length, s
  /// Births per emitter are floor(e) plus one with probability frac(e), e the expected count.
  /// A particle is born at the emitter position jittered uniformly over a square of side
  /// `length` in the sheet's tangent plane, moving at birth_speed along +n if n.z >= 0 else -n
  /// (both sides alternating when |n.z| < vertical_band). Each is born at a uniform time within
  /// the coming step: its age starts at minus that delay (in (-dt, 0]) and the next step(dt)
  /// carries it through the rest of the step only.
  /// @param side if given, per emitter: +1 or -1 to be born on that side of its normal (the
  /// outside of a closed shell), 0 for the rule above (the upper side; both near vertical)
  void emit(const RowMatX3& pos, const RowMatX3& normal, const Eigen::VectorXd& length, double dt,
            const Eigen::VectorXd* side = nullptr);

  /// @brief Advance all live particles by dt in a wind (m/s): exact exponential integration of
  /// cooling, drag and buoyancy, then an Ornstein-Uhlenbeck turbulent kick; age; kill the dead.
  void step(double dt, const Eigen::Vector3d& wind);

  /// @brief Move live particle i to x and take off its velocity's component against the unit
  /// normal n (it met a surface it must not cross: OutsideKeeper).
  void push_out(int i, const Eigen::Vector3d& x, const Eigen::Vector3d& n);

  /// @brief Number of live particles.
  int count() const { return count_; }
  /// @brief Pool capacity.
  int capacity() const { return params_.capacity; }
  /// @brief Births refused because the pool was full, since construction.
  std::uint64_t dropped() const { return dropped_; }
  /// @brief Particles born since construction (including those that have died).
  std::uint64_t born() const { return next_id_ - dropped_; }
  /// @brief The parameters in force.
  const ParticleParams& params() const { return params_; }

  /// @brief Live positions (count x 3), m.
  Eigen::Block<const RowMatX3, Eigen::Dynamic, 3, true> positions() const { return pos_.topRows(count_); }
  /// @brief Live velocities (count x 3), m/s.
  Eigen::Block<const RowMatX3, Eigen::Dynamic, 3, true> velocities() const { return vel_.topRows(count_); }
  /// @brief Live temperatures (count), K above ambient.
  Eigen::VectorBlock<const Eigen::VectorXd> temperatures() const { return temp_.head(count_); }
  /// @brief Live ages (count), s.
  Eigen::VectorBlock<const Eigen::VectorXd> ages() const { return age_.head(count_); }
  /// @brief Live lifetimes (count), s: a particle dies when its age reaches this.
  Eigen::VectorBlock<const Eigen::VectorXd> lifetimes() const { return life_.head(count_); }
  /// @brief Birth serial numbers of the live particles (count).
  const std::vector<std::uint64_t>& ids() const { return id_; }
  /// @brief Steps taken since construction.
  std::uint64_t steps() const { return steps_; }

 private:
  void birth(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double length, double dt, double side);
  void compact();

  ParticleParams params_;
  RowMatX3 pos_, vel_;
  Eigen::VectorXd temp_, age_, life_;
  std::vector<std::uint64_t> id_;  // size == count_ (reserved to capacity)
  int count_ = 0;
  std::uint64_t next_id_ = 0;
  std::uint64_t dropped_ = 0;
  std::uint64_t emit_calls_ = 0;
  std::uint64_t steps_ = 0;
};

/// @brief Validate parameters; throws std::invalid_argument naming the field and its bound.
void validate(const ParticleParams& params);

}  // namespace thinburn
