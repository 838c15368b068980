#include "particles.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "threads.hpp"

namespace thinburn {
namespace {

// Counter-based randomness: every draw is a pure function of its key, so the order in
// which threads visit particles cannot change any result, and no std:: distribution
// (whose output differs between standard libraries) is involved.
constexpr std::uint64_t kGolden = 0x9e3779b97f4a7c15ULL;
constexpr std::uint64_t kTagEmit = 0x454d4954ULL;
constexpr std::uint64_t kTagBirth = 0x42495254ULL;
constexpr std::uint64_t kTagStep = 0x53544550ULL;
constexpr std::uint64_t kTagDelay = 0x44454c59ULL;

std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

std::uint64_t hash_key(std::uint64_t seed, std::uint64_t tag, std::uint64_t a, std::uint64_t b) {
  std::uint64_t h = mix64(seed + kGolden);
  h = mix64(h ^ (tag + kGolden));
  h = mix64(h ^ (a + kGolden));
  return mix64(h ^ (b + kGolden));
}

// splitmix64 started from a hashed key.
class Stream {
 public:
  explicit Stream(std::uint64_t key) : s_(key) {}
  std::uint64_t next() { return mix64(s_ += kGolden); }
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  // Zero mean, unit variance, from the sum of four 32-bit uniforms (Irwin-Hall): no libm.
  double normal() {
    const std::uint64_t a = next(), b = next();
    const double s = double(a >> 32) + double(a & 0xffffffffULL) + double(b >> 32) +
                     double(b & 0xffffffffULL);
    return (s * 0x1.0p-32 - 2.0) * 1.7320508075688772;  // sqrt(12 / 4)
  }

 private:
  std::uint64_t s_;
};

// (1 - exp(-r t)) / r, continuous at r = 0.
double one_minus_exp_over(double r, double t) {
  const double x = r * t;
  return std::abs(x) < 1e-12 ? t : -std::expm1(-x) / r;
}

// phi(t) = int_0^t exp(-k (t - s)) exp(-c s) ds: the velocity response to a forcing that
// decays at rate c under a drag of rate k. Stable when k ~ c.
double phi(double k, double c, double t) {
  if (std::abs(k - c) * t > 1e-3) return (std::exp(-c * t) - std::exp(-k * t)) / (k - c);
  const double m = 0.5 * (k + c), h2 = 0.25 * (k - c) * (k - c) * t * t;
  return t * std::exp(-m * t) * (1.0 + h2 / 6.0 + h2 * h2 / 120.0);
}

// psi(t) = int_0^t phi(s) ds by composite 5-point Gauss-Legendre; the integrand is smooth
// and the panels are short against 1/max(k, c), so the result is exact to rounding. It is
// one scalar per step, so its cost does not matter.
double psi(double k, double c, double t) {
  static const double xg[5] = {-0.9061798459386640, -0.5384693101056831, 0.0,
                               0.5384693101056831, 0.9061798459386640};
  static const double wg[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                               0.4786286704993665, 0.2369268850561891};
  const int panels = int(std::min(1.0e4, std::ceil(2.0 * std::max(k, c) * t) + 1.0));
  const double hp = t / panels;
  double sum = 0.0;
  for (int q = 0; q < panels; ++q) {
    const double mid = (q + 0.5) * hp;
    for (int g = 0; g < 5; ++g) sum += wg[g] * phi(k, c, mid + 0.5 * hp * xg[g]);
  }
  return 0.5 * hp * sum;
}

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

bool finite_nonneg(double v) { return std::isfinite(v) && v >= 0.0; }

// An orthonormal tangent pair for a unit normal (branch on the sign to avoid cancellation).
void tangents(const Eigen::Vector3d& n, Eigen::Vector3d& t1, Eigen::Vector3d& t2) {
  const double s = n.z() >= 0.0 ? 1.0 : -1.0;
  const double a = -1.0 / (s + n.z());
  const double b = n.x() * n.y() * a;
  t1 = Eigen::Vector3d(1.0 + s * n.x() * n.x() * a, s * b, -s * n.x());
  t2 = Eigen::Vector3d(b, s + n.y() * n.y() * a, -n.y());
}

}  // namespace

const std::vector<param::Field<ParticleParams>>& ParticleParams::fields() {
  using P = ParticleParams;
  using namespace param;
  static const std::vector<Field<P>> table = {
      field("capacity", &P::capacity, within(1, 100000000), "particles the pool holds; births beyond are dropped"),
      field("birth_rate", &P::birth_rate, at_least(0), "particles per second per metre of fire front"),
      field("temperature0", &P::temperature0, above(0), "K above ambient at birth"),
      field("cooling", &P::cooling, at_least(0), "1/s: T = temperature0 exp(-cooling age)"),
      field("lifetime", &P::lifetime, above(0), "s: the mean lifetime"),
      field("lifetime_jitter", &P::lifetime_jitter, within(0, 1, false, true),
           "lifetimes uniform in lifetime [1 - j, 1 + j]"),
      field("buoyancy", &P::buoyancy, at_least(0), "m/s^2 upward at temperature0, proportional to T"),
      field("drag", &P::drag, at_least(0), "1/s: relaxation rate of the velocity toward the wind"),
      field("turbulence", &P::turbulence, at_least(0), "m/s: rms of each velocity component's fluctuation"),
      field("birth_speed", &P::birth_speed, at_least(0), "m/s along the emitting side's normal"),
      field("vertical_band", &P::vertical_band, within(0, 1), "emitters with |n.z| below this emit on both sides"),
      field("seed", &P::seed, "seed of the random stream (a Simulation's shell sets it from its own seed)"),
  };
  return table;
}

void validate(const ParticleParams& p) { param::check_all(ParticleParams::fields(), p); }

ParticleSystem::ParticleSystem(const ParticleParams& params) : params_(params) {
  validate(params_);
  const int n = params_.capacity;
  pos_.resize(n, 3);
  vel_.resize(n, 3);
  temp_.resize(n);
  age_.resize(n);
  life_.resize(n);
  id_.reserve(n);
}

void ParticleSystem::emit(const RowMatX3& pos, const RowMatX3& normal,
                          const Eigen::VectorXd& length, double dt, const Eigen::VectorXd* side) {
  const Eigen::Index k = pos.rows();
  require(normal.rows() == k, "normal must have as many rows as pos");
  require(length.size() == k, "length must have one entry per row of pos");
  require(!side || side->size() == k, "side must have one entry per row of pos");
  require(std::isfinite(dt) && dt >= 0.0, "dt must be finite and >= 0");
  require(pos.allFinite(), "pos must be finite");
  require(normal.allFinite(), "normal must be finite");
  for (Eigen::Index i = 0; i < k; ++i) {
    require(finite_nonneg(length(i)), "length must be finite and >= 0");
    require(normal.row(i).norm() > 1e-12, "normal must be nonzero");
    require(params_.birth_rate * length(i) * dt < 1e15,
            "length: birth_rate * length * dt must be < 1e15");
  }
  const std::uint64_t call = emit_calls_++;
  for (Eigen::Index i = 0; i < k; ++i) {
    const double expected = params_.birth_rate * length(i) * dt;
    const double whole = std::floor(expected);
    Stream rng(hash_key(params_.seed, kTagEmit, call, std::uint64_t(i)));
    const std::uint64_t n = std::uint64_t(whole) + (rng.uniform() < expected - whole ? 1 : 0);
    const Eigen::Vector3d p = pos.row(i).transpose();
    const Eigen::Vector3d nn = normal.row(i).transpose().normalized();
    for (std::uint64_t j = 0; j < n; ++j) {
      if (count_ >= params_.capacity) {  // the rest of this emitter's births are dropped
        next_id_ += n - j;
        dropped_ += n - j;
        break;
      }
      birth(p, nn, length(i), dt, side ? (*side)(i) : 0.0);
    }
  }
}

void ParticleSystem::push_out(int i, const Eigen::Vector3d& x, const Eigen::Vector3d& n) {
  require(i >= 0 && i < count_, "push_out: no live particle of that index");
  pos_.row(i) = x.transpose();
  const double vn = vel_.row(i).dot(n.transpose());
  if (vn < 0.0) vel_.row(i) -= vn * n.transpose();
}

void ParticleSystem::birth(const Eigen::Vector3d& p, const Eigen::Vector3d& n, double length, double dt,
                           double given_side) {
  const std::uint64_t id = next_id_++;
  Stream rng(hash_key(params_.seed, kTagBirth, id, 0));
  double side = n.z() >= 0.0 ? 1.0 : -1.0;
  if (std::abs(n.z()) < params_.vertical_band) side = (id & 1U) ? -1.0 : 1.0;
  if (given_side != 0.0) side = given_side > 0.0 ? 1.0 : -1.0;
  Eigen::Vector3d t1, t2;
  tangents(n, t1, t2);
  const double a = (rng.uniform() - 0.5) * length, b = (rng.uniform() - 0.5) * length;
  const double j = params_.lifetime_jitter;
  const int r = count_++;
  pos_.row(r) = (p + a * t1 + b * t2).transpose();
  vel_.row(r) = (side * params_.birth_speed * n).transpose();
  temp_(r) = params_.temperature0;
  // Born at a uniform time within the step, not all at its start: a step then carries each
  // newborn only through the part of the step it lives (its age starts at minus its delay), so
  // the heat that particles deliver (sampled at the steps' ends) does not depend on dt. Births
  // all at the start lost 1 - c dt e^{-c dt} / (1 - e^{-c dt}) of it (16 % at 1/24 s, cooling 8/s).
  age_(r) = -dt * Stream(hash_key(params_.seed, kTagDelay, id, 0)).uniform();
  life_(r) = params_.lifetime * (1.0 + j * (2.0 * rng.uniform() - 1.0));
  id_.push_back(id);
}

void ParticleSystem::step(double dt, const Eigen::Vector3d& wind) {
  require(std::isfinite(dt) && dt >= 0.0, "dt must be finite and >= 0");
  require(wind.allFinite(), "wind must be finite");
  const std::uint64_t step_index = steps_++;
  const double k = params_.drag, c = params_.cooling;
  const double ec = std::exp(-c * dt), ek = std::exp(-k * dt);
  const double e1k = one_minus_exp_over(k, dt);
  const double ph = phi(k, c, dt), ps = psi(k, c, dt);
  const double kick = params_.turbulence * std::sqrt(-std::expm1(-2.0 * k * dt));
  const double lift = params_.buoyancy / params_.temperature0;
  const std::uint64_t seed = params_.seed;
  const int n = count_;
  parallel_for(0, n, 64, [&](long i_) {
    const int i = static_cast<int>(i_);
    const double g = lift * temp_(i);
    // A particle born within this step (age < 0) moves only for the part it lives.
    // (A step shorter than its delay leaves it unborn, still at its emitter, for the next.)
    const bool newborn = age_(i) < 0.0;
    const double h = newborn ? std::clamp(dt + age_(i), 0.0, dt) : dt;
    const double ekh = newborn ? std::exp(-k * h) : ek, e1kh = newborn ? one_minus_exp_over(k, h) : e1k;
    for (int a = 0; a < 3; ++a) {
      const double rel = vel_(i, a) - wind(a);
      pos_(i, a) += wind(a) * h + rel * e1kh;
      vel_(i, a) = wind(a) + rel * ekh;
    }
    pos_(i, 2) += g * (newborn ? psi(k, c, h) : ps);
    vel_(i, 2) += g * (newborn ? phi(k, c, h) : ph);
    if (kick > 0.0) {
      Stream rng(hash_key(seed, kTagStep, id_[i], step_index));
      const double kh = newborn ? params_.turbulence * std::sqrt(-std::expm1(-2.0 * k * h)) : kick;
      for (int a = 0; a < 3; ++a) vel_(i, a) += kh * rng.normal();
    }
    temp_(i) *= newborn ? std::exp(-c * h) : ec;
    age_(i) += dt;
  });
  compact();
}

void ParticleSystem::compact() {
  int w = 0;
  for (int r = 0; r < count_; ++r) {
    if (age_(r) >= life_(r)) continue;
    if (w != r) {
      pos_.row(w) = pos_.row(r);
      vel_.row(w) = vel_.row(r);
      temp_(w) = temp_(r);
      age_(w) = age_(r);
      life_(w) = life_(r);
      id_[w] = id_[r];
    }
    ++w;
  }
  count_ = w;
  id_.resize(w);
}

}  // namespace thinburn
