// A sparse block LDL^T factorization for systems made of 3x3 blocks (one block row and column
// per lattice vertex): A = P^T L D L^T P with L unit block-lower-triangular and D block-diagonal
// (dense symmetric 3x3 blocks). It serves the implicit solve's preconditioner (implicit_solver.cpp).
//
// Why not Eigen's SimplicialLDLT: that factorization is scalar, so every one of the 9 entries of
// a block carries its own row index and its own scattered update; the lattice's system is
// made of dense 3x3 blocks, and working on whole blocks cuts the index traffic ninefold and lets
// each update run as a small dense product. The ordering is the same (Eigen's AMD, applied to
// the block graph), so the fill is the scalar factorization's, counted in blocks.
#pragma once

#include <Eigen/Core>

#include <vector>

namespace thinburn {

class BlockLdlt {
 public:
  /// Symbolic analysis of a symmetric block pattern of n block rows and columns, given as its
  /// lower triangle by columns: column j's blocks are rows[col_start[j] .. col_start[j+1]), all
  /// >= j (the diagonal block j may be listed or not; it is always part of the pattern).
  void analyze(int n, const std::vector<int>& col_start, const std::vector<int>& rows);

  /// Numeric factorization. values holds one column-major 3x3 block (9 doubles) per entry of
  /// the `rows` given to analyze, in that order; diagonal blocks must be listed there to be
  /// nonzero. Only the lower triangle of a diagonal block is read. Returns false when a pivot
  /// block is not positive definite (A is not SPD); solve must not be called then.
  bool factorize(const double* values);

  /// x <- A^-1 x, x of length 3n.
  void solve(double* x) const;

  int size() const { return n_; }
  /// Blocks stored in L below the diagonal (the fill-in included).
  int off_diagonal_blocks() const { return static_cast<int>(l_row_.size()); }
  /// Multiply-adds of one factorize (its 3x3 block products, 27 each), from the pattern.
  double factor_work() const { return factor_work_; }
  /// Multiply-adds of one solve: each block of L twice and each pivot once, 9 a block.
  double solve_work() const { return 9.0 * (2.0 * static_cast<double>(l_row_.size()) + n_); }

 private:
  using Block = Eigen::Matrix3d;
  int n_ = 0;
  double factor_work_ = 0.0;
  std::vector<int> perm_;      // perm_[new] = old block index
  std::vector<int> l_start_;   // L by columns (new indices): rows l_row_[l_start_[j]..l_start_[j+1])
  std::vector<int> l_row_;
  std::vector<Block> l_val_;
  std::vector<int> r_start_;   // L by rows: for row i, the (column, position in l_row_) pairs
  std::vector<int> r_col_;
  std::vector<int> r_pos_;
  std::vector<int> a_start_;   // per new column j: where its entries of A go
  std::vector<int> a_src_;     //   the entry's index in `values`
  std::vector<int> a_row_;     //   its row in the new numbering (>= j)
  std::vector<char> a_trans_;  //   stored as its transpose (the entry lay in the upper triangle)
  std::vector<Block> d_, d_inv_;
  std::vector<Block> work_;    // one block column during factorize, indexed by row
  mutable std::vector<Eigen::Vector3d> y_;
};

}  // namespace thinburn
