#include "implicit_solver.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "block_ldlt.hpp"
#include "dynamics.hpp"
#include "threads.hpp"

namespace thinburn {
namespace {

constexpr int kDotChunk = 4096;

// Sum of a[i] * b[i] in fixed chunks summed in order: the same bits for any thread count.
double det_dot(const double* a, const double* b, int len, double* partial) {
  const int chunks = (len + kDotChunk - 1) / kDotChunk;
  parallel_for(0, chunks, kDotChunk, [&](long c_) {
    const int c = static_cast<int>(c_);
    double s = 0.0;
    const int end = std::min(len, (c + 1) * kDotChunk);
    for (int i = c * kDotChunk; i < end; ++i) s += a[i] * b[i];
    partial[c] = s;
  });
  double t = 0.0;
  for (int c = 0; c < chunks; ++c) t += partial[c];
  return t;
}

}  // namespace

// The implicit system over the active vertices, lower triangle of 3x3 blocks by columns, and its
// sparse block LDL^T factorization (block_ldlt.hpp), the conjugate gradients' preconditioner.
// The pattern depends only on the active set: values are refilled in the order the pattern was
// built, and the symbolic analysis (AMD ordering, elimination tree) is redone only when the
// active set changes. The numeric factorization is kept over substeps and steps (masses,
// lengths and contacts change slowly), and over changes of the active set, until the work of
// the iterations it costs beyond a fresh factor's adds up to the work of a new factorization
// (rent or buy), a solve needs more than refactor_iterations iterations, or the active set has
// moved too far from the factored one.
struct ImplicitSolver::Factor {
  std::vector<int> active;      // the active set the pattern was built for
  std::vector<int> slot;        // per vertex: its position in `active`, -1 if not in it
  std::vector<int> blk_start;   // per active vertex: its column's 3x3 blocks in blk_row/blk_spring
  std::vector<int> blk_row;     // row slot of each block; the vertex itself (diagonal) first
  std::vector<int> blk_spring;  // the spring of an off-diagonal block, -1 on the diagonal
  std::vector<std::pair<int, int>> sort_buf;
  std::vector<double> values;   // 9 per block of blk_row, column-major
  BlockLdlt ldlt;
  Eigen::VectorXd rhs;
  bool analysed = false;  // ldlt holds the symbolic analysis of `active`
  bool valid = false;     // ldlt holds a numeric factorization of `active`'s system
  bool stale = false;     // the last solve took too many iterations: refactor before the next
  double iteration_work = 0.0;  // multiply-adds of one iteration: A's product and the factor's solve
  int fresh_iterations = -1;    // iterations of the first solve after the factorization
  double rent = 0.0;            // multiply-adds of the iterations beyond those since then
};

ImplicitSolver::ImplicitSolver(const View& view) : s_(view), factor_(std::make_unique<Factor>()) {}

ImplicitSolver::~ImplicitSolver() = default;

void ImplicitSolver::resize(std::size_t springs, std::size_t vertices) {
  // 6 per spring (Jacobian blocks), 27 per vertex (diagonal block and the two blocks of its row
  // of the couple-block preconditioner), 3 per vertex for each of the CG vectors and the
  // forces and the right-hand side's motion, and the dot-product partials.
  ns_ = springs;
  n_ = vertices;
  work_.assign(6 * ns_ + 27 * n_ + 8 * 3 * n_ + (3 * n_) / kDotChunk + 2, 0.0);
  factor_ = std::make_unique<Factor>();  // the pattern may have gained blocks
}

ImplicitSolver::Buffers ImplicitSolver::buffers() {
  Buffers B;
  double* q = work_.data();
  B.jac = q;
  q += 6 * ns_;
  B.diag = q;
  q += 9 * n_;
  B.pinv = q;
  q += 18 * n_;
  double** vecs[8] = {&B.f, &B.b, &B.dv, &B.r, &B.z, &B.p, &B.Ap, &B.w};
  for (double** v : vecs) {
    *v = q;
    q += 3 * n_;
  }
  B.partial = q;
  return B;
}

void ImplicitSolver::build_jacobi(double h) {
  Buffers B = buffers();
  const int na = static_cast<int>(s_.active.size());
  const double h2 = h * h;
  // Couple-block Jacobi: the top-bottom spring is the stiffest, so both vertices of a couple are
  // inverted together (6 x 6); a vertex whose partner is not active gets its 3 x 3 inverse.
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = s_.active[a], pa = s_.slot[v ^ 1];
    if (pa < 0) {
      mat3(B.pinv, 2 * a) = mat3(B.diag, a).inverse();
      mat3(B.pinv, 2 * a + 1).setZero();
      return;
    }
    Eigen::Matrix<double, 6, 6> C;
    const Eigen::Matrix3d J = load_sym(B.jac + 6 * s_.couple_spring[v / 2]);
    C.topLeftCorner<3, 3>() = mat3(B.diag, a);
    C.bottomRightCorner<3, 3>() = mat3(B.diag, pa);
    C.topRightCorner<3, 3>() = -h2 * J;
    C.bottomLeftCorner<3, 3>() = -h2 * J;
    const Eigen::Matrix<double, 6, 6> Ci = C.inverse();
    mat3(B.pinv, 2 * a) = Ci.topLeftCorner<3, 3>();
    mat3(B.pinv, 2 * a + 1) = Ci.topRightCorner<3, 3>();
  });
}

void ImplicitSolver::apply_A(double h, const double* in, double* out) {
  const int na = static_cast<int>(s_.active.size());
  const double h2 = h * h;
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    vec3(out, a) = row_of_A(h2, a, in);
  });
}

Eigen::Vector3d ImplicitSolver::row_of_A(double h2, int a, const double* in) {
  Buffers B = buffers();
  const int v = s_.active[a];
  Eigen::Vector3d y = mat3(B.diag, a) * Eigen::Map<const Eigen::Vector3d>(in + 3 * a);
  for (int q = s_.incidence.start[v]; q < s_.incidence.start[v + 1]; ++q) {
    const int so = s_.slot[s_.incidence.other[q]];
    if (so >= 0)
      y -= h2 * load_sym(B.jac + 6 * s_.incidence.spring[q]) * Eigen::Map<const Eigen::Vector3d>(in + 3 * so);
  }
  return y;
}

Eigen::Vector3d ImplicitSolver::constraint_impulse(double h, int a) {
  Buffers B = buffers();
  return row_of_A(h * h, a, B.dv) - vec3(B.b, a);
}

void ImplicitSolver::precondition(const double* in, double* out) {
  Buffers B = buffers();
  const int na = static_cast<int>(s_.active.size());
  if (precond_ldlt_) {
    // z = S P S r: the filter S zeroes the contacts' v_z in and out. Vertices of the factored
    // set go through the factor (the others of that set see a zero residual), the rest through
    // their diagonal block.
    Factor& f = *factor_;
    f.rhs.setZero();
    for (int a = 0; a < na; ++a) {
      const int fs = f.slot[s_.active[a]];
      if (fs < 0) continue;
      for (int i = 0; i < 3; ++i) f.rhs[3 * fs + i] = in[3 * a + i];
      s_.contacts.filter(s_.active[a], f.rhs.data() + 3 * fs);
    }
    f.ldlt.solve(f.rhs.data());
    for (int a = 0; a < na; ++a) {
      const int fs = f.slot[s_.active[a]];
      if (fs >= 0)
        vec3(out, a) = Eigen::Map<const Eigen::Vector3d>(f.rhs.data() + 3 * fs);
      else
        vec3(out, a) = mat3(B.pinv, 2 * a) * Eigen::Map<const Eigen::Vector3d>(in + 3 * a);
      s_.contacts.filter(s_.active[a], out + 3 * a);
    }
    return;
  }
  parallel_for(0, na, kRowCost, [&](long a_) {
    const int a = static_cast<int>(a_);
    const int v = s_.active[a], pa = s_.slot[v ^ 1];
    Eigen::Vector3d y = mat3(B.pinv, 2 * a) * Eigen::Map<const Eigen::Vector3d>(in + 3 * a);
    if (pa >= 0) y += mat3(B.pinv, 2 * a + 1) * Eigen::Map<const Eigen::Vector3d>(in + 3 * pa);
    s_.contacts.filter(v, y.data());  // the filter of Baraff and Witkin's modified PCG
    vec3(out, a) = y;
  });
}

bool ImplicitSolver::use_ldlt() const {
  if (s_.p.preconditioner == Preconditioner::Auto)
    return static_cast<int>(s_.active.size()) <= s_.p.ldlt_max_vertices || choice_.ldlt;
  return s_.p.preconditioner == Preconditioner::Ldlt;
}

void ImplicitSolver::account(bool ldlt, int iterations, bool factorized) {
  // Above ldlt_max_vertices, Auto measures what each preconditioner costs here: a factor that
  // is kept over many solves (a curtain in a steady wind: 11 iterations a step against
  // Jacobi's 1127) wins by far, one that must be redone as the awake set grows (a hot spot
  // spreading over a large sheet) loses by as much. Work is counted in multiply-adds from the
  // pattern and the iteration counts, not in seconds, so the pick, and the result, is the same
  // on any machine and thread count.
  ldlt_solves_ += ldlt;
  if (s_.p.preconditioner != Preconditioner::Auto || static_cast<int>(s_.active.size()) <= s_.p.ldlt_max_vertices)
    return;
  Choice& c = choice_;
  if (ldlt != c.ldlt) return;  // the factor failed and Jacobi stood in
  // Multiply-adds: A's product is 9 a block (one per vertex and per spring end); Jacobi's
  // preconditioner 2 blocks a vertex per iteration and a 6 x 6 inverse (about 216) a vertex per
  // solve; the factor's solve and its factorization as BlockLdlt counts them.
  const Factor& f = *factor_;
  double work;
  if (ldlt) {
    work = iterations * f.iteration_work + (factorized ? f.ldlt.factor_work() : 0.0);
  } else {
    double a_blocks = 0.0;
    for (int v : s_.active) a_blocks += 1 + s_.incidence.start[v + 1] - s_.incidence.start[v];
    const double na = static_cast<double>(s_.active.size());
    work = iterations * (9.0 * a_blocks + 18.0 * na) + 216.0 * na;
  }
  c.sum += work;
  ++c.since_measured[0], ++c.since_measured[1];
  const int k = c.ldlt ? 1 : 0, other = 1 - k;
  ++c.run;
  // A trial ends as soon as it has cost more than the pick would over the whole trial: the
  // loser's try is then bounded by the winner's cost (a Jacobi try on a kept factor's curtain
  // ran 1500 iterations a solve).
  const bool lost = c.trying && c.per_solve[other] >= 0 && c.sum > c.per_solve[other] * Choice::kTrial[k];
  if (c.run < Choice::kTrial[k] && !lost) return;
  c.per_solve[k] = c.sum / c.run;  // each run measures the one that ran
  c.since_measured[k] = 0;
  c.sum = 0.0, c.run = 0;
  if (c.per_solve[other] < 0 || c.since_measured[other] >= c.retrial) {
    c.ldlt = !c.ldlt;  // try the other
    c.trying = true;
    return;
  }
  const bool pick = c.per_solve[1] <= c.per_solve[0];
  if (c.trying) {
    // A trial that loses sends the next one twice as far off; one that wins starts afresh.
    c.retrial = pick == c.ldlt ? Choice::kRetrial : std::min(2 * c.retrial, Choice::kMaxRetrial);
    c.trying = false;
  }
  c.ldlt = pick;
}

void ImplicitSolver::factor_pattern() {
  Factor& f = *factor_;
  if (f.analysed && f.active == s_.active) return;
  const int na = static_cast<int>(s_.active.size());
  f.active = s_.active;
  f.slot = s_.slot;
  f.valid = false;
  f.blk_start.assign(1, 0);
  f.blk_row.clear();
  f.blk_spring.clear();
  for (int a = 0; a < na; ++a) {
    const int v = s_.active[a];
    f.sort_buf.clear();
    for (int q = s_.incidence.start[v]; q < s_.incidence.start[v + 1]; ++q)
      if (s_.slot[s_.incidence.other[q]] > a) f.sort_buf.emplace_back(s_.slot[s_.incidence.other[q]], s_.incidence.spring[q]);
    std::sort(f.sort_buf.begin(), f.sort_buf.end());  // rows ascending within each column
    f.blk_row.push_back(a);
    f.blk_spring.push_back(-1);
    for (const auto& [row, spring] : f.sort_buf) {
      f.blk_row.push_back(row);
      f.blk_spring.push_back(spring);
    }
    f.blk_start.push_back(static_cast<int>(f.blk_row.size()));
  }
  f.values.resize(9 * f.blk_row.size());
  f.rhs.resize(3 * na);
  f.ldlt.analyze(na, f.blk_start, f.blk_row);
  f.analysed = true;
  // A's product: a block per spring end and per vertex, 9 multiply-adds each.
  double a_blocks = na;
  for (int v : s_.active) a_blocks += s_.incidence.start[v + 1] - s_.incidence.start[v];
  f.iteration_work = 9.0 * a_blocks + f.ldlt.solve_work();
}

void ImplicitSolver::factor_fill(double h) {
  // A = M (1 + h c) + h W + h^2 J, with each floor contact's v_z row and column replaced by the
  // identity, as the filtered conjugate gradients see it. Blocks are written column-major.
  Factor& f = *factor_;
  Buffers B = buffers();
  const int na = static_cast<int>(s_.active.size());
  const double h2 = h * h;
  const int sym[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};  // store_sym's layout
  for (int a = 0; a < na; ++a) {
    const int va = s_.active[a];
    for (int b = f.blk_start[a]; b < f.blk_start[a + 1]; ++b) {
      const int r = f.blk_row[b];
      const int vr = s_.active[r];
      double* val = f.values.data() + 9 * b;
      if (r == a) {
        const auto D = mat3(B.diag, a);
        for (int i = 0; i < 3; ++i)
          for (int ii = 0; ii < 3; ++ii)
            val[3 * i + ii] = (s_.contacts.filtered(va, i) || s_.contacts.filtered(va, ii)) ? (ii == i ? 1.0 : 0.0) : D(ii, i);
        continue;
      }
      const double* J = B.jac + 6 * f.blk_spring[b];
      for (int i = 0; i < 3; ++i)
        for (int ii = 0; ii < 3; ++ii)
          val[3 * i + ii] = (s_.contacts.filtered(va, i) || s_.contacts.filtered(vr, ii)) ? 0.0 : -h2 * J[sym[ii][i]];
    }
  }
}

void ImplicitSolver::refresh_factor(double h) {
  // A factor of another active set F still preconditions this one, S: F's part of the residual
  // goes through A_FF^-1, the vertices outside F through their diagonal blocks (an SPD block
  // diagonal). It is refactored when it is stale, or when S and F differ by more than a quarter.
  Factor& f = *factor_;
  if (f.valid && !f.stale) {
    int outside = 0;
    for (int v : s_.active) outside += f.slot[v] < 0;
    const int ns = static_cast<int>(s_.active.size()), nf = static_cast<int>(f.active.size());
    if (4 * outside <= ns && nf - (ns - outside) <= ns / 4) return;
  }
  factor_pattern();
  factor_fill(h);
  // A failure is not expected (A is symmetric positive definite); the solve then falls back to
  // Jacobi.
  f.valid = f.ldlt.factorize(f.values.data());
  ++factorizations_;
  f.stale = false;
  f.fresh_iterations = -1;
  f.rent = 0.0;
}

void ImplicitSolver::charge_rent(int iterations) {
  // Rent or buy: a kept factor costs, at each solve, the iterations it takes beyond what the
  // fresh factor took; once those add up to one factorization's work, refactoring pays. So a
  // factor that serves well is kept however long, and one that serves badly is soon replaced,
  // at most about twice the cheaper of the two. Counted in multiply-adds, not seconds, so that
  // the choice, and the result, is the same on any machine and thread count.
  Factor& f = *factor_;
  if (f.fresh_iterations < 0) f.fresh_iterations = iterations;
  f.rent += std::max(0, iterations - f.fresh_iterations) * f.iteration_work;
  if (iterations > s_.p.refactor_iterations || f.rent >= f.ldlt.factor_work()) f.stale = true;
}

void ImplicitSolver::prepare_preconditioner(double h) {
  Buffers B = buffers();
  precond_ldlt_ = use_ldlt() && factor_->valid;
  if (!precond_ldlt_) {
    build_jacobi(h);
    return;
  }
  // Vertices outside the factored set are preconditioned by their diagonal block.
  const int na = static_cast<int>(s_.active.size());
  for (int a = 0; a < na; ++a)
    if (factor_->slot[s_.active[a]] < 0) mat3(B.pinv, 2 * a) = mat3(B.diag, a).inverse();
}

int ImplicitSolver::rent_budget() const {
  // Iterations the kept factor may take in this solve before their excess over a fresh factor's
  // costs a factorization: rent or buy within the solve, so that one bad solve (a factor of
  // another awake set: 1023 iterations in a step of a hanging curtain) is bounded too. The rent
  // charged by earlier solves is left to charge_rent, which refactors before the next solve:
  // counting it here as well bought factors more often on the demo scenes, for the same
  // iterations.
  const Factor& f = *factor_;
  if (!precond_ldlt_ || f.fresh_iterations < 0) return s_.p.cg_max_iterations;
  const double extra = f.ldlt.factor_work() / f.iteration_work;
  return static_cast<int>(std::min<double>(s_.p.cg_max_iterations, f.fresh_iterations + std::ceil(extra)));
}

void ImplicitSolver::residual(double h) {
  // r = S (b - A dv), S the contacts' filter.
  Buffers B = buffers();
  const int na = static_cast<int>(s_.active.size()), N = 3 * na;
  apply_A(h, B.dv, B.Ap);
  for (int i = 0; i < N; ++i) B.r[i] = B.b[i] - B.Ap[i];
  for (int a = 0; a < na; ++a) s_.contacts.filter(s_.active[a], B.r + 3 * a);
}

int ImplicitSolver::cg(double h, double ref, double floor_abs, int max_iterations, bool& converged) {
  // Modified PCG (Baraff and Witkin 1998) from the start value in B.dv: constrained DOFs start
  // at their prescribed value (v_z -> 0) and every search direction is filtered to leave them
  // there.
  Buffers B = buffers();
  const int na = static_cast<int>(s_.active.size()), N = 3 * na;
  auto axpy = [&](double alpha, const double* xv, double* y) {  // y += alpha x
    parallel_for(0, N, kAxpyCost, [&](long i) { y[i] += alpha * xv[i]; });
  };
  const double tol = std::max(s_.p.cg_tolerance * ref, floor_abs);
  converged = std::sqrt(det_dot(B.r, B.r, N, B.partial)) <= floor_abs;
  if (converged) return 0;
  int iterations = 0;
  precondition(B.r, B.p);
  double rz = det_dot(B.r, B.p, N, B.partial);
  while (iterations < max_iterations) {
    ++iterations;
    apply_A(h, B.p, B.Ap);
    for (int a = 0; a < na; ++a) s_.contacts.filter(s_.active[a], B.Ap + 3 * a);
    const double pAp = det_dot(B.p, B.Ap, N, B.partial);
    if (!(pAp > 0.0)) {
      converged = true;  // nothing left to descend along (as good as this solve gets)
      break;
    }
    const double alpha = rz / pAp;
    axpy(alpha, B.p, B.dv);
    axpy(-alpha, B.Ap, B.r);
    if (std::sqrt(det_dot(B.r, B.r, N, B.partial)) <= tol) {
      converged = true;
      break;
    }
    precondition(B.r, B.z);
    const double rz_new = det_dot(B.r, B.z, N, B.partial);
    const double beta = rz_new / rz;
    rz = rz_new;
    parallel_for(0, N, kAxpyCost, [&](long i) { B.p[i] = B.z[i] + beta * B.p[i]; });
  }
  return iterations;
}

int ImplicitSolver::solve(double h) {
  Buffers B = buffers();
  const int na = static_cast<int>(s_.active.size()), N = 3 * na;
  const int factored_before = factorizations_;
  if (use_ldlt()) refresh_factor(h);
  prepare_preconditioner(h);
  // The tolerance's scale, fixed for the solve (a restart must not tighten it): the larger of
  // the start residual and the filtered b (in z until the first preconditioning; b stays as
  // assembled, constraint_impulse reads it).
  residual(h);
  for (int i = 0; i < N; ++i) B.z[i] = B.b[i];
  for (int a = 0; a < na; ++a) s_.contacts.filter(s_.active[a], B.z + 3 * a);
  const double ref = std::max(std::sqrt(det_dot(B.r, B.r, N, B.partial)), std::sqrt(det_dot(B.z, B.z, N, B.partial)));
  // Absolute floor: a residual below cg_velocity_tolerance times the mass norm changes the
  // velocities by less than about that (A >= M), whatever rounding-level right-hand side a
  // resting sheet has; without it such a sheet would iterate on rounding noise.
  double mass2 = 0.0;
  for (int v : s_.active) mass2 += 3.0 * s_.mass(v) * s_.mass(v);
  const double floor_abs = s_.p.cg_velocity_tolerance * std::sqrt(mass2);
  bool converged = false;
  int iterations = cg(h, ref, floor_abs, rent_budget(), converged);
  int since_factor = iterations;
  if (!converged && precond_ldlt_ && iterations < s_.p.cg_max_iterations) {
    // The kept factor has cost a factorization's worth of extra iterations: buy a fresh one and
    // go on from where the iterations got to.
    factor_->stale = true;
    refresh_factor(h);
    prepare_preconditioner(h);
    residual(h);  // the true residual, not the one the iterations updated
    since_factor = cg(h, ref, floor_abs, s_.p.cg_max_iterations - iterations, converged);
    iterations += since_factor;
  }
  if (precond_ldlt_) charge_rent(since_factor);
  account(precond_ldlt_, iterations, factorizations_ > factored_before);
  return iterations;
}

}  // namespace thinburn
