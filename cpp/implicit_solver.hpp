#pragma once
/// @brief The linear solve of the lattice's implicit substeps (docs/dynamics.md §4): A dv = b,
/// A = M (1 + h c) + h W + h^2 J over the active vertices, by Baraff and Witkin's modified
/// preconditioned conjugate gradients, filtered at the floor contacts, preconditioned by a
/// sparse block LDL^T factorization of A (block_ldlt.hpp) kept while it serves, or by
/// couple-block Jacobi.
///
/// The dynamics assembles A's blocks and b into buffers(); the solver reads the lattice
/// through a narrow view: the active set and its slots, the springs' incidence, each couple's
/// top-bottom spring, the masses and the contacts' filter.
#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <vector>

#include "contact.hpp"
#include "lattice.hpp"

namespace thinburn {

struct DynamicsParams;

/// Work per entry of an axpy in kParallelWork's units (threads.hpp): about 11, so an axpy over
/// fewer than 3000 entries stays on one thread.
constexpr long kAxpyCost = 11;

// Symmetric 3x3 blocks stored as 6 numbers (xx, yy, zz, xy, xz, yz), and 3-vectors and 3x3
// blocks (column-major) of flat buffers, by slot.
inline void store_sym(double* out, const Eigen::Matrix3d& J) {
  out[0] = J(0, 0), out[1] = J(1, 1), out[2] = J(2, 2);
  out[3] = J(0, 1), out[4] = J(0, 2), out[5] = J(1, 2);
}
inline Eigen::Matrix3d load_sym(const double* s) {
  Eigen::Matrix3d J;
  J << s[0], s[3], s[4], s[3], s[1], s[5], s[4], s[5], s[2];
  return J;
}
inline Eigen::Map<Eigen::Vector3d> vec3(double* base, int slot) {
  return Eigen::Map<Eigen::Vector3d>(base + 3 * slot);
}
inline Eigen::Map<Eigen::Matrix3d> mat3(double* base, int slot) {
  return Eigen::Map<Eigen::Matrix3d>(base + 9 * slot);
}

class ImplicitSolver {
 public:
  /// @brief The lattice as the solve sees it, kept by reference (the dynamics owns it).
  struct View {
    const std::vector<int>& active;         // the vertices solved for
    const std::vector<int>& slot;           // per vertex: its position in active, -1 if not in it
    const SpringIncidence& incidence;
    const std::vector<int>& couple_spring;  // per couple: its top-bottom spring
    const Eigen::VectorXd& mass;            // kg per vertex
    const Contacts& contacts;               // the filter of prescribed velocity components
    const DynamicsParams& p;
  };
  /// @brief Work buffers, by active slot: [jacobian blocks 6/spring (by spring) | diagonal
  /// blocks 9/vertex | preconditioner 18/vertex | f, b, dv, r, z, p, Ap, w: 3/vertex each | dot
  /// partials]. The dynamics fills jac (store_sym), diag, f and b (w: its scratch for b), and
  /// the start value dv.
  struct Buffers {
    double *jac, *diag, *pinv, *f, *b, *dv, *r, *z, *p, *Ap, *w, *partial;
  };

  explicit ImplicitSolver(const View& view);
  ~ImplicitSolver();

  /// @brief Size the buffers for `springs` springs and `vertices` control vertices, and forget
  /// the factorization (the system's pattern changed).
  void resize(std::size_t springs, std::size_t vertices);
  Buffers buffers();
  /// @brief Solve A dv = b from the start value in buffers().dv (filtered components at their
  /// prescribed values) for substep h; returns the iterations taken.
  int solve(double h);
  /// @brief (A dv - b) at active slot a, from the buffers' dv and b: on a contact's filtered
  /// components, the impulse the floor gave it this substep (kg m/s); about 0 on free ones.
  Eigen::Vector3d constraint_impulse(double h, int a);
  /// @brief Block LDL^T factorizations since reset_count.
  int factorizations() const { return factorizations_; }
  /// @brief Solves preconditioned by the factor since reset_count.
  int ldlt_solves() const { return ldlt_solves_; }
  void reset_count() { factorizations_ = ldlt_solves_ = 0; }

 private:
  struct Factor;
  // Auto above ldlt_max_vertices: Jacobi for kTrial[0] solves, then the factor for kTrial[1]
  // (enough to spread a factorization over), then the one whose solves cost fewer
  // multiply-adds; the other is tried again after `retrial` solves, twice as long after each
  // try that confirms the pick.
  struct Choice {
    static constexpr int kTrial[2] = {4, 24}, kRetrial = 240, kMaxRetrial = 7680;
    bool ldlt = false;                 // the one in use
    bool trying = false;               // ... on trial against the pick
    double per_solve[2] = {-1, -1};    // measured work per solve: [0] Jacobi, [1] LDL^T; -1 unknown
    int since_measured[2] = {0, 0};    // solves since each was last measured
    int retrial = kRetrial;
    double sum = 0.0;                  // the pick's work over its current run
    int run = 0;                       // solves in that run
  };
  bool use_ldlt() const;
  void account(bool ldlt, int iterations, bool factorized);
  void refresh_factor(double h);
  void charge_rent(int iterations);
  void build_jacobi(double h);
  void factor_pattern();
  void factor_fill(double h);
  void apply_A(double h, const double* in, double* out);
  // (A in) at active slot a, h2 = h^2.
  Eigen::Vector3d row_of_A(double h2, int a, const double* in);
  void precondition(const double* in, double* out);
  // Jacobi's blocks, or the factor (and the diagonal blocks of the vertices outside it).
  void prepare_preconditioner(double h);
  // Iterations the solve may take on a kept factor before refactoring pays.
  int rent_budget() const;
  // buffers().r = the filtered b - A dv.
  void residual(double h);
  // Conjugate gradients from buffers().dv and its residual in buffers().r until the residual is
  // below max(cg_tolerance ref, floor_abs) (converged) or max_iterations ran; returns the
  // iterations.
  int cg(double h, double ref, double floor_abs, int max_iterations, bool& converged);

  View s_;
  std::size_t ns_ = 0, n_ = 0;      // springs and vertices the buffers are sized for
  std::vector<double> work_;        // CG and Jacobian buffers, reused
  std::unique_ptr<Factor> factor_;
  int factorizations_ = 0;          // since reset_count
  int ldlt_solves_ = 0;             // since reset_count
  Choice choice_;
  bool precond_ldlt_ = false;       // the solve in progress uses factor_
};

}  // namespace thinburn
