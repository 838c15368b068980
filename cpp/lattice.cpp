#include "lattice.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "threads.hpp"

namespace thinburn {
namespace {

constexpr double kParamSlack = 1e-9;
// deform's work: points go in blocks of kDeformBlock (one call of the vectorised kernel each);
// one point costs about 1 of kParallelWork's units (threads.hpp), so meshes below about 32k
// vertices deform on one thread.
constexpr Eigen::Index kDeformBlock = 1024;
constexpr long kPointCost = 1;
// The kept points' copy out goes in blocks of 64k rows (1.5 MB), each far above the pool's
// threshold: a mesh of a single block stays on the calling thread.
constexpr Eigen::Index kCopyBlock = 1 << 16;

// Weights of one lattice axis at coordinate x over the three nodes base, base+1, base+2
// (base + 2 may be unused: weight 0). Linear: two nodes.
struct Axis1D {
  int base = 0;
  double w[3] = {0, 0, 0};
};

Axis1D linear_axis(double x, int M) {
  Axis1D a;
  a.base = std::min(static_cast<int>(std::floor(x)), M - 2);
  const double f = x - a.base;
  a.w[0] = 1.0 - f;
  a.w[1] = f;
  return a;
}

// Uniform quadratic B-spline centred on the nodes; the nodes beyond the ends are linear
// extrapolations (ghost = 2 x_end - x_next), which keeps partition of unity and linear
// precision and leaves every weight >= 0 (near an end the spline is the linear one).
Axis1D bspline_axis(double x, int M) {
  if (M < 3) return linear_axis(x, M);
  const int c = std::clamp(static_cast<int>(std::lround(x)), 0, M - 1);
  const double d = x - c;
  double node_w[3] = {0.5 * (0.5 - d) * (0.5 - d), 0.75 - d * d, 0.5 * (0.5 + d) * (0.5 + d)};
  Axis1D a;
  a.base = std::clamp(c - 1, 0, M - 3);
  for (int q = 0; q < 3; ++q) {
    const int node = c - 1 + q;
    if (node < 0) {  // ghost -1 = 2 x_0 - x_1
      a.w[0 - a.base] += 2.0 * node_w[q];
      a.w[1 - a.base] -= node_w[q];
    } else if (node > M - 1) {  // ghost M = 2 x_{M-1} - x_{M-2}
      a.w[M - 1 - a.base] += 2.0 * node_w[q];
      a.w[M - 2 - a.base] -= node_w[q];
    } else {
      a.w[node - a.base] += node_w[q];
    }
  }
  return a;
}

double checked_param(double x, double hi, const char* what, Eigen::Index row) {
  if (!std::isfinite(x) || x < -kParamSlack || x > hi + kParamSlack)
    throw std::invalid_argument("params: " + std::string(what) + " of row " + std::to_string(row) +
                                " is " + std::to_string(x) + ", outside [0, " +
                                std::to_string(hi) + "]");
  return std::clamp(x, 0.0, hi);
}

// Four doubles of the displacement table (xyz and a pad). With GCC and Clang a vector
// extension, which the compiler maps onto whatever SIMD the function is built for; elsewhere
// Eigen's fixed-size array. The same IEEE operations per lane either way.
#if defined(__GNUC__)
typedef double Lanes4 __attribute__((vector_size(32)));
// By reference, not by value: a 32-byte vector returned by value changes the ABI between the
// AVX2 and the default build of a function.
inline void load4(Lanes4& v, const double* p) { std::memcpy(&v, p, sizeof v); }
inline void zero4(Lanes4& v) { v = Lanes4{0.0, 0.0, 0.0, 0.0}; }
#else
using Lanes4 = Eigen::Array4d;
inline void load4(Lanes4& v, const double* p) { v = Eigen::Map<const Eigen::Array4d>(p); }
inline void zero4(Lanes4& v) { v.setZero(); }
#endif

// GCC on x86-64 Linux also builds an AVX2 copy of the deform kernel, chosen at load time on
// CPUs that have it (a 4-double layer is then one instruction, not two): no global flags, and
// no FMA, so both copies round identically.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define THINBURN_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define THINBURN_AVX2_CLONE
#endif

// Deformed positions from the per-couple displacement table: 8 doubles per couple, bottom
// (x, y, z, 0) then top (x, y, z, 0). Each point reads its own stencil and writes its own row,
// summing w * ((1 - r) * d_bottom + r * d_top) in stencil order from zero, adding the rest point
// and raising z to z_min: the result does not depend on the thread count. Returns true when a
// couple index is out of range (couple 0 stands in; the caller throws). Points lo..hi-1, or
// with a list (CachedDeform's groups) the points list[lo..hi-1]: the same arithmetic per point.
template <int St>
THINBURN_AVX2_CLONE bool deform_range(const Embedding& e, const double* table, int couples,
                                      Eigen::Ref<RowMatX3>& out, double z_min, Eigen::Index lo,
                                      Eigen::Index hi, const std::int32_t* list = nullptr) {
  const std::int32_t* couple = e.couple.data();
  const double* weight = e.weight.data();
  const double* r_of = e.r.data();
  const double* rest = e.rest.data();
  double* dst = out.data();
  const Eigen::Index stride = out.outerStride();
  const auto limit = static_cast<std::uint32_t>(couples);
  bool bad = false;
  for (Eigen::Index k = lo; k < hi; ++k) {
    const Eigen::Index p = list ? list[k] : k;
    const double r = r_of[p], s = 1.0 - r;
    Lanes4 acc, bottom, top;
    zero4(acc);
    bool ok = true;
    for (int q = 0; q < St; ++q) {
      std::uint32_t c = static_cast<std::uint32_t>(couple[p * St + q]);
      ok &= c < limit;
      c = c < limit ? c : 0;
      const double w = weight[p * St + q];
      const double* d = table + 8 * std::size_t(c);
      load4(bottom, d);
      load4(top, d + 4);
      acc += w * (s * bottom + r * top);
    }
    bad |= !ok;
    double* o = dst + p * stride;
    o[0] = rest[3 * p] + acc[0];
    o[1] = rest[3 * p + 1] + acc[1];
    o[2] = std::max(rest[3 * p + 2] + acc[2], z_min);
  }
  return bad;
}

// Blocks of kDeformBlock points, each a call of the cloned (vectorised) kernel.
template <int St>
bool deform_points(const Embedding& e, const double* table, int couples, Eigen::Ref<RowMatX3>& out,
                   double z_min) {
  const Eigen::Index n = e.size();
  const long blocks = static_cast<long>((n + kDeformBlock - 1) / kDeformBlock);
  std::atomic<bool> bad{false};
  parallel_for(0, blocks, kDeformBlock * kPointCost, [&](long b) {
    const Eigen::Index lo = b * kDeformBlock, hi = std::min<Eigen::Index>(n, lo + kDeformBlock);
    if (deform_range<St>(e, table, couples, out, z_min, lo, hi)) bad.store(true, std::memory_order_relaxed);
  });
  return bad.load();
}

}  // namespace

FfdLattice::FfdLattice(int M, const RowMatX3& rest) : M_(M), couples_(M * M), rest_(rest), pos_(rest) {
  if (M < 2) throw std::invalid_argument("M must be >= 2, got " + std::to_string(M));
  if (rest.rows() != 2 * Eigen::Index(M) * M)
    throw std::invalid_argument("rest must have 2*M*M = " + std::to_string(2 * M * M) +
                                " rows, got " + std::to_string(rest.rows()));
  if (!rest.allFinite()) throw std::invalid_argument("rest must be finite");
}

FfdLattice::FfdLattice(const RowMatX3& rest, int M, int couples) : M_(M), couples_(couples), rest_(rest), pos_(rest) {}

FfdLattice FfdLattice::on_surface(int couples, const RowMatX3& rest) {
  if (couples < 3) throw std::invalid_argument("couples must be >= 3, got " + std::to_string(couples));
  if (rest.rows() != 2 * Eigen::Index(couples))
    throw std::invalid_argument("rest must have 2*couples = " + std::to_string(2 * couples) +
                                " rows, got " + std::to_string(rest.rows()));
  if (!rest.allFinite()) throw std::invalid_argument("rest must be finite");
  return FfdLattice(rest, 0, couples);
}

Embedding FfdLattice::embed(const RowMatX3& params, const RowMatX3& rest_points,
                            LatticeInterp interp) const {
  if (params.rows() != rest_points.rows())
    throw std::invalid_argument("rest_points must have as many rows as params (" +
                                std::to_string(params.rows()) + "), got " +
                                std::to_string(rest_points.rows()));
  if (!rest_points.allFinite()) throw std::invalid_argument("rest_points must be finite");
  if (M_ == 0) throw std::invalid_argument("embed: this lattice follows a control surface, not a grid");
  const int side = interp == LatticeInterp::QuadraticBSpline && M_ >= 3 ? 3 : 2;
  Embedding e;
  e.stencil = side * side;
  const Eigen::Index n = params.rows();
  e.couple.assign(std::size_t(n) * e.stencil, 0);
  e.weight.assign(std::size_t(n) * e.stencil, 0.0);
  e.r.resize(n);
  e.rest = rest_points;
  const double hi = M_ - 1;
  for (Eigen::Index p = 0; p < n; ++p) {
    const double s = checked_param(params(p, 0), hi, "s", p);
    const double t = checked_param(params(p, 1), hi, "t", p);
    e.r(p) = checked_param(params(p, 2), 1.0, "r", p);
    const std::size_t slot = std::size_t(p) * e.stencil;
    plane_stencil(s, t, interp, e.couple.data() + slot, e.weight.data() + slot);
  }
  return e;
}

int FfdLattice::plane_stencil(double s, double t, LatticeInterp interp, int* couple, double* w) const {
  if (M_ == 0) throw std::invalid_argument("plane_stencil: this lattice follows a control surface, not a grid");
  const bool spline = interp == LatticeInterp::QuadraticBSpline && M_ >= 3;
  const int side = spline ? 3 : 2;
  s = std::clamp(s, 0.0, double(M_ - 1));
  t = std::clamp(t, 0.0, double(M_ - 1));
  const Axis1D ai = spline ? bspline_axis(s, M_) : linear_axis(s, M_);
  const Axis1D aj = spline ? bspline_axis(t, M_) : linear_axis(t, M_);
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b) {
      couple[a * side + b] = (ai.base + a) * M_ + (aj.base + b);
      w[a * side + b] = ai.w[a] * aj.w[b];
    }
  return side * side;
}

void FfdLattice::deform(const Embedding& e, Eigen::Ref<RowMatX3> out, double z_min) const {
  const Eigen::Index n = e.size();
  if (out.rows() != n)
    throw std::invalid_argument("out must have " + std::to_string(n) + " rows, got " +
                                std::to_string(out.rows()));
  if (e.couple.size() != std::size_t(n) * e.stencil || e.weight.size() != e.couple.size() ||
      e.rest.rows() != n || (e.stencil != 4 && e.stencil != 9))
    throw std::invalid_argument("embedding is inconsistent (stencil, couples, weights, rest)");
  if (std::isnan(z_min)) throw std::invalid_argument("z_min must not be NaN");
  // Each control vertex's displacement once per call, not once per point that uses it. The
  // buffer belongs to the calling thread: concurrent deforms (the GIL is released) never share it.
  thread_local std::vector<double> table;
  const int couples = couples_;
  displacement_table(table);
  const bool bad = e.stencil == 4 ? deform_points<4>(e, table.data(), couples, out, z_min)
                                  : deform_points<9>(e, table.data(), couples, out, z_min);
  if (bad) throw std::invalid_argument("embedding does not fit this lattice");
}

void FfdLattice::displacement_table(std::vector<double>& table) const {
  table.resize(8 * std::size_t(couples_));
  for (int v = 0; v < 2 * couples_; ++v) {  // vertex v = 2 * couple + layer: slot 4 v
    for (int d = 0; d < 3; ++d) table[4 * v + d] = pos_(v, d) - rest_(v, d);
    table[4 * v + 3] = 0.0;
  }
}

CachedDeform::CachedDeform(const Embedding& e, int couples, double tolerance)
    : points_(e.size()), tolerance_(tolerance), moved_(couples, 0) {
  if (!std::isfinite(tolerance) || tolerance < 0.0)
    throw std::invalid_argument("CachedDeform: tolerance must be finite and >= 0, got " + std::to_string(tolerance));
  // Points grouped by their stencil's first couple: every point of a group reads the same
  // couples (a grid stencil is fixed by its first), so one moved couple redoes only the points
  // around it, not whole rows of the mesh.
  const Eigen::Index n = e.size();
  group_offset_.assign(couples + 1, 0);
  for (Eigen::Index p = 0; p < n; ++p) {
    for (int q = 0; q < e.stencil; ++q) {
      const int c = e.couple[std::size_t(p) * e.stencil + q];
      if (c < 0 || c >= couples) throw std::invalid_argument("embedding does not fit this lattice");
    }
    ++group_offset_[e.couple[std::size_t(p) * e.stencil] + 1];
  }
  for (int c = 0; c < couples; ++c) group_offset_[c + 1] += group_offset_[c];
  group_points_.resize(n);
  std::vector<int> fill(group_offset_.begin(), group_offset_.end() - 1);
  for (Eigen::Index p = 0; p < n; ++p) group_points_[fill[e.couple[std::size_t(p) * e.stencil]]++] = static_cast<std::int32_t>(p);
  // Drop the empty groups; keep each group's couples (those of its first point).
  std::vector<int> offset(1, 0);
  for (int c = 0; c < couples; ++c) {
    const int lo = group_offset_[c], hi = group_offset_[c + 1];
    if (lo == hi) continue;
    offset.push_back(hi);
    const std::size_t first = std::size_t(group_points_[lo]) * e.stencil;
    group_couples_.insert(group_couples_.end(), e.couple.begin() + first, e.couple.begin() + first + e.stencil);
  }
  group_offset_.swap(offset);
  stencil_ = e.stencil;
}

void CachedDeform::deform_into(const FfdLattice& lattice, const Embedding& e, double z_min, Eigen::Ref<RowMatX3> out) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (static_cast<int>(moved_.size()) != lattice.couples() || e.size() != points_ || e.stencil != stencil_)
    throw std::invalid_argument("CachedDeform: the embedding or the lattice is not the one it was made for");
  if (out.rows() != points_)
    throw std::invalid_argument("out must have " + std::to_string(points_) + " rows, got " + std::to_string(out.rows()));
  if (std::isnan(z_min)) throw std::invalid_argument("z_min must not be NaN");
  thread_local std::vector<double> table;
  lattice.displacement_table(table);
  const long points = moved_points(table, z_min);
  const int couples = lattice.couples();
  if (2 * points > points_) {
    // Most of the mesh moved: straight into out in the mesh's order, as FfdLattice::deform
    // (no copy; the groups' order jumps between rows). The kept positions go stale.
    deform_all(e, table.data(), couples, z_min, out);
    positions_valid_ = false;
    kept_.swap(table);  // every point now reads this table
  } else {
    positions_.resize(points_, 3);
    Eigen::Ref<RowMatX3> kept(positions_);
    if (!positions_valid_) {
      deform_all(e, table.data(), couples, z_min, kept);
      kept_.swap(table);
    } else {
      redone_ = points;
      const double* tab = table.data();  // the caller's: table is thread_local, the helpers' own are empty
      const long per_group = std::max<long>(1, points / std::max<long>(1, static_cast<long>(dirty_.size())));
      parallel_for(0, static_cast<long>(dirty_.size()), per_group * kPointCost, [&](long i) {
        const long g = dirty_[i];
        // The couples were checked at construction: the kernel cannot meet one out of range.
        if (stencil_ == 4) deform_range<4>(e, tab, couples, kept, z_min, group_offset_[g], group_offset_[g + 1], group_points_.data());
        else deform_range<9>(e, tab, couples, kept, z_min, group_offset_[g], group_offset_[g + 1], group_points_.data());
      });
      keep_moved_couples(table);
    }
    positions_valid_ = true;
    // memcpy where out's rows are packed (numpy's C order): Eigen's copy into a Ref with a
    // run-time stride went row by row, 10 % of a film frame. In blocks over the threads: one
    // thread's copy of the film's 24 MB was most of a frame that redoes few vertices.
    if (out.outerStride() == 3) {
      const long blocks = static_cast<long>((points_ + kCopyBlock - 1) / kCopyBlock);
      parallel_for(0, blocks, kCopyBlock * kPointCost, [&](long b) {
        const Eigen::Index lo = b * kCopyBlock, rows = std::min<Eigen::Index>(points_ - lo, kCopyBlock);
        std::memcpy(out.data() + 3 * lo, positions_.data() + 3 * lo, sizeof(double) * 3 * std::size_t(rows));
      });
    } else {
      out = positions_;
    }
  }
  z_min_ = z_min;
  kept_valid_ = true;
}

// Why every point stays within 2 tol of the full deform (each coordinate, tol = tolerance_).
// Take a group g this call does not redo, last computed from an earlier call's table T'; K_c
// is the kept rows of a couple c of its stencil. (a) When g was computed, c either moved (then
// K_c = T'_c) or not (|T'_c - K_c| <= tol entrywise). (b) K_c has not changed since: it
// changes only when c moves, and that redoes every group reading c, g among them. (c) c has not
// moved now: |T_c - K_c| <= tol. So |T_c - T'_c| <= 2 tol in every entry. A point's coordinate
// is rest + sum_q w_q ((1 - r) d_bottom + r d_top), r in [0, 1]: it is off by at most
// 2 tol sum_q |w_q|. The grid embeddings' weights are products of axis weights >= 0 that sum
// to 1 (linear_axis; bspline_axis's end ghosts keep them >= 0), so 2 tol, up to the rounding
// of the two sums (ulps of the coordinates). The floor's max(z, z_min) moves no value farther
// apart, and a new z_min redoes every point. tol = 0 is the bitwise comparison: an unmoved
// couple's entries equal the kept ones bit for bit, and so the points are the full deform's.
long CachedDeform::moved_points(const std::vector<double>& table, double z_min) {
  const bool all = !kept_valid_ || z_min != z_min_;
  for (std::size_t c = 0; c < moved_.size(); ++c)
    moved_[c] = all || couple_moved(&table[8 * c], &kept_[8 * c]);
  dirty_.clear();
  long points = 0;
  for (long g = 0; g < groups(); ++g)
    for (int q = 0; q < stencil_; ++q)
      if (moved_[group_couples_[std::size_t(g) * stencil_ + q]]) {
        dirty_.push_back(g);
        points += group_offset_[g + 1] - group_offset_[g];
        break;
      }
  return points;
}

bool CachedDeform::couple_moved(const double* now, const double* kept) const {
  // Bitwise at 0, so the cache stays exact whatever the values (-0.0, a NaN kept as it was).
  if (tolerance_ == 0.0) return std::memcmp(now, kept, 8 * sizeof(double)) != 0;
  // "Not within": a NaN or an infinite displacement counts as moved.
  for (int k = 0; k < 8; ++k)
    if (!(std::fabs(now[k] - kept[k]) <= tolerance_)) return true;
  return false;
}

// After a partial redo: only the moved couples take the new rows. An unmoved couple keeps the
// rows of its last redo, so a drift below the tolerance each call still adds up to a redo.
void CachedDeform::keep_moved_couples(const std::vector<double>& table) {
  for (std::size_t c = 0; c < moved_.size(); ++c)
    if (moved_[c]) std::memcpy(&kept_[8 * c], &table[8 * c], 8 * sizeof(double));
}

void CachedDeform::deform_all(const Embedding& e, const double* table, int couples, double z_min, Eigen::Ref<RowMatX3> out) {
  redone_ = points_;
  if (stencil_ == 4) deform_points<4>(e, table, couples, out, z_min);
  else deform_points<9>(e, table, couples, out, z_min);
}

Eigen::VectorXd FfdLattice::scatter(const Embedding& e, const Eigen::VectorXd& values) const {
  if (values.size() != e.size())
    throw std::invalid_argument("values must have " + std::to_string(e.size()) +
                                " entries, got " + std::to_string(values.size()));
  Eigen::VectorXd out = Eigen::VectorXd::Zero(size());
  const int st = e.stencil;
  for (Eigen::Index p = 0; p < e.size(); ++p)
    for (int q = 0; q < st; ++q) {
      const std::size_t slot = std::size_t(p) * st + q;
      const int c = e.couple[slot];
      if (c < 0 || c >= couples_) throw std::invalid_argument("embedding does not fit this lattice");
      out(2 * c) += e.weight[slot] * (1.0 - e.r(p)) * values(p);
      out(2 * c + 1) += e.weight[slot] * e.r(p) * values(p);
    }
  return out;
}

std::vector<Eigen::Matrix3d> shape_operators(const RowMatX3& rest, const LatticeTopology& topo) {
  auto axis = [&](int c) -> Eigen::Vector3d {
    const Eigen::Vector3d a = (rest.row(2 * c + 1) - rest.row(2 * c)).transpose();
    return a.norm() > 0 ? Eigen::Vector3d(a.normalized()) : Eigen::Vector3d::Zero();
  };
  std::vector<Eigen::Matrix3d> out(topo.couples, Eigen::Matrix3d::Zero());
  for (int c = 0; c < topo.couples; ++c) {
    const Eigen::Vector3d n = axis(c);
    if (n.squaredNorm() == 0.0) continue;
    const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);
    // Unknowns (s11, s12, s22) in the basis (t1, t2); each neighbour gives two equations.
    Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    bool turns = false;
    for (int q = topo.nbr_offset[c]; q < topo.nbr_offset[c + 1]; ++q) {
      const int o = topo.nbr_index[q];
      const Eigen::Vector3d e = couple_centre(rest, o) - couple_centre(rest, c), dn = axis(o) - n;
      turns = turns || dn.dot(t1) != 0.0 || dn.dot(t2) != 0.0;
      const double a1 = e.dot(t1), a2 = e.dot(t2);
      const Eigen::Vector3d row1(a1, a2, 0.0), row2(0.0, a1, a2);
      N += row1 * row1.transpose() + row2 * row2.transpose();
      rhs += dn.dot(t1) * row1 + dn.dot(t2) * row2;
    }
    if (!turns) continue;  // exactly flat here: zero, not a least-squares rounding
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(N);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * N.trace())) continue;
    const Eigen::Vector3d sv = ldlt.solve(rhs);
    Eigen::Matrix<double, 3, 2> T;
    T << t1, t2;
    Eigen::Matrix2d S2;
    S2 << sv(0), sv(1), sv(1), sv(2);
    out[c] = T * S2 * T.transpose();
  }
  return out;
}

std::vector<std::array<int, 3>> grid_corners(int M) {
  std::vector<std::array<int, 3>> out;
  if (M < 2) return out;
  for (const auto& [i, j] : {std::pair{0, 0}, {0, M - 1}, {M - 1, 0}, {M - 1, M - 1}}) {
    const int di = i == 0 ? 1 : -1, dj = j == 0 ? 1 : -1;
    out.push_back({i * M + j, (i + di) * M + j, i * M + j + dj});
  }
  return out;
}

LatticeTopology grid_topology(int M) {
  if (M < 2) throw std::invalid_argument("M must be >= 2, got " + std::to_string(M));
  LatticeTopology t;
  t.couples = M * M;
  t.grid_side = M;
  auto index = [M](int i, int j, int k) { return ((i * M) + j) * 2 + k; };
  auto add = [&t](int a, int b, std::uint8_t kind) {
    t.spring_a.push_back(a);
    t.spring_b.push_back(b);
    t.kind.push_back(kind);
  };
  for (int k = 0; k < 2; ++k)
    for (int i = 0; i < M; ++i)
      for (int j = 0; j < M; ++j) {
        const int v = index(i, j, k);
        if (j + 1 < M) add(v, index(i, j + 1, k), 0);
        if (i + 1 < M) add(v, index(i + 1, j, k), 0);
        if (i + 1 < M && j + 1 < M) {
          add(v, index(i + 1, j + 1, k), 1);
          add(index(i, j + 1, k), index(i + 1, j, k), 1);
        }
        if (j + 2 < M) add(v, index(i, j + 2, k), 2);
        if (i + 2 < M) add(v, index(i + 2, j, k), 2);
      }
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < M; ++j) {
      add(index(i, j, 0), index(i, j, 1), 3);
      if (j + 1 < M) {
        add(index(i, j, 0), index(i, j + 1, 1), 4);
        add(index(i, j, 1), index(i, j + 1, 0), 4);
      }
      if (i + 1 < M) {
        add(index(i, j, 0), index(i + 1, j, 1), 4);
        add(index(i, j, 1), index(i + 1, j, 0), 4);
      }
    }
  t.nbr_offset.assign(1, 0);
  const int di[4] = {-1, 1, 0, 0}, dj[4] = {0, 0, -1, 1};
  for (int i = 0; i < M; ++i)
    for (int j = 0; j < M; ++j) {
      for (int q = 0; q < 4; ++q) {
        const int oi = i + di[q], oj = j + dj[q];
        if (oi >= 0 && oi < M && oj >= 0 && oj < M) t.nbr_index.push_back(oi * M + oj);
      }
      t.nbr_offset.push_back(static_cast<int>(t.nbr_index.size()));
    }
  return t;
}

}  // namespace thinburn
