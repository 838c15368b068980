#include "block_ldlt.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>

namespace thinburn {
namespace {

using Block = Eigen::Matrix3d;

// Fill-reducing order of the block graph: Eigen's approximate minimum degree. Returns
// perm[new] = old.
std::vector<int> amd_order(int n, const std::vector<int>& col_start, const std::vector<int>& rows) {
  if (n == 0) return {};
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(2 * rows.size() + n);
  for (int j = 0; j < n; ++j) {
    t.emplace_back(j, j, 1.0);
    for (int q = col_start[j]; q < col_start[j + 1]; ++q) {
      t.emplace_back(rows[q], j, 1.0);
      t.emplace_back(j, rows[q], 1.0);
    }
  }
  Eigen::SparseMatrix<double> pattern(n, n);
  pattern.setFromTriplets(t.begin(), t.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p;
  Eigen::AMDOrdering<int>()(pattern, p);
  return std::vector<int>(p.indices().data(), p.indices().data() + n);
}

}  // namespace

void BlockLdlt::analyze(int n, const std::vector<int>& col_start, const std::vector<int>& rows) {
  if (n < 0 || static_cast<int>(col_start.size()) != n + 1 || col_start[n] != static_cast<int>(rows.size()))
    throw std::invalid_argument("BlockLdlt::analyze: col_start must have n + 1 entries ending at rows.size()");
  if (col_start[0] != 0) throw std::invalid_argument("BlockLdlt::analyze: col_start must start at 0");
  for (int j = 0; j < n; ++j) {
    if (col_start[j + 1] < col_start[j]) throw std::invalid_argument("BlockLdlt::analyze: col_start must not decrease");
    for (int q = col_start[j]; q < col_start[j + 1]; ++q)
      if (rows[q] < j || rows[q] >= n) throw std::invalid_argument("BlockLdlt::analyze: a row outside [j, n)");
  }
  n_ = n;
  perm_ = amd_order(n, col_start, rows);
  std::vector<int> inv(n);
  for (int k = 0; k < n; ++k) inv[perm_[k]] = k;

  // Where each entry of A goes in the new numbering: the lower triangle of new column
  // min(i, j), transposed when the new order flips it.
  std::vector<std::vector<int>> by_col(n);
  for (int j = 0; j < n; ++j)
    for (int q = col_start[j]; q < col_start[j + 1]; ++q) by_col[std::min(inv[rows[q]], inv[j])].push_back(q);
  a_start_.assign(1, 0);
  a_src_.clear();
  a_row_.clear();
  a_trans_.clear();
  std::vector<int> old_col(rows.size());
  for (int j = 0; j < n; ++j)
    for (int q = col_start[j]; q < col_start[j + 1]; ++q) old_col[q] = j;
  for (int j = 0; j < n; ++j) {
    for (int q : by_col[j]) {
      const int ri = inv[rows[q]], ci = inv[old_col[q]];
      a_src_.push_back(q);
      a_row_.push_back(std::max(ri, ci));
      a_trans_.push_back(ri < ci);
    }
    a_start_.push_back(static_cast<int>(a_src_.size()));
  }

  // L's pattern, column by column: A's rows below j and the patterns of j's children in the
  // elimination tree (a column's parent is its first row below the diagonal).
  std::vector<std::vector<int>> children(n);
  std::vector<int> mark(n, -1);
  l_start_.assign(1, 0);
  l_row_.clear();
  for (int j = 0; j < n; ++j) {
    const int begin = static_cast<int>(l_row_.size());
    mark[j] = j;
    auto add = [&](int i) {
      if (mark[i] != j) {
        mark[i] = j;
        l_row_.push_back(i);
      }
    };
    for (int q = a_start_[j]; q < a_start_[j + 1]; ++q) add(a_row_[q]);
    for (int c : children[j])
      for (int q = l_start_[c]; q < l_start_[c + 1]; ++q) add(l_row_[q]);
    std::sort(l_row_.begin() + begin, l_row_.end());
    l_start_.push_back(static_cast<int>(l_row_.size()));
    if (static_cast<int>(l_row_.size()) > begin) children[l_row_[begin]].push_back(j);
  }

  // The same pattern by rows, for the left-looking updates: row i lists the columns k < i
  // with a block L_ik, in increasing k.
  r_start_.assign(n + 1, 0);
  for (int i : l_row_) ++r_start_[i + 1];
  for (int i = 0; i < n; ++i) r_start_[i + 1] += r_start_[i];
  r_col_.resize(l_row_.size());
  r_pos_.resize(l_row_.size());
  std::vector<int> fill(r_start_.begin(), r_start_.end() - 1);
  for (int k = 0; k < n; ++k)
    for (int q = l_start_[k]; q < l_start_[k + 1]; ++q) {
      const int slot = fill[l_row_[q]]++;
      r_col_[slot] = k;
      r_pos_[slot] = q;
    }
  // Column k's c blocks below the diagonal each update the pivot and the blocks below them in
  // their row of the later columns: c (c + 1) / 2 + c products of two blocks, plus the pivot's
  // own inverse and the scaling of the column by it.
  factor_work_ = 0.0;
  for (int k = 0; k < n; ++k) {
    const double c = l_start_[k + 1] - l_start_[k];
    factor_work_ += 27.0 * (0.5 * c * (c + 1.0) + 2.0 * c + 2.0);
  }
  l_val_.resize(l_row_.size());
  d_.resize(n);
  d_inv_.resize(n);
  work_.assign(n, Block::Zero());
  y_.resize(n);
}

bool BlockLdlt::factorize(const double* values) {
  // Left-looking, one block column at a time:
  //   D_j  = A_jj - sum_k L_jk D_k L_jk^T
  //   L_ij = (A_ij - sum_k L_ik D_k L_jk^T) D_j^-1,  over the columns k < j with L_jk != 0.
  for (int j = 0; j < n_; ++j) {
    work_[j].setZero();
    for (int q = l_start_[j]; q < l_start_[j + 1]; ++q) work_[l_row_[q]].setZero();
    for (int q = a_start_[j]; q < a_start_[j + 1]; ++q) {
      const Eigen::Map<const Block> a(values + 9 * a_src_[q]);
      const int i = a_row_[q];
      if (i == j)
        work_[i] += Block(a.selfadjointView<Eigen::Lower>());
      else if (a_trans_[q])
        work_[i] += a.transpose();
      else
        work_[i] += a;
    }
    for (int s = r_start_[j]; s < r_start_[j + 1]; ++s) {
      const int k = r_col_[s], p = r_pos_[s];
      const Block y = l_val_[p] * d_[k];  // L_jk D_k; (L_jk D_k)^T = D_k L_jk^T as D_k is symmetric
      work_[j].noalias() -= y * l_val_[p].transpose();
      for (int q = p + 1; q < l_start_[k + 1]; ++q) work_[l_row_[q]].noalias() -= l_val_[q] * y.transpose();
    }
    d_[j] = 0.5 * (work_[j] + work_[j].transpose());  // rounding keeps it only nearly symmetric
    Eigen::LLT<Block> llt(d_[j]);
    if (llt.info() != Eigen::Success) return false;
    d_inv_[j] = llt.solve(Block::Identity());
    for (int q = l_start_[j]; q < l_start_[j + 1]; ++q) l_val_[q] = work_[l_row_[q]] * d_inv_[j];
  }
  return true;
}

void BlockLdlt::solve(double* x) const {
  for (int k = 0; k < n_; ++k) y_[k] = Eigen::Map<const Eigen::Vector3d>(x + 3 * perm_[k]);
  for (int j = 0; j < n_; ++j) {  // L y = b
    const Eigen::Vector3d yj = y_[j];
    for (int q = l_start_[j]; q < l_start_[j + 1]; ++q) y_[l_row_[q]].noalias() -= l_val_[q] * yj;
  }
  for (int j = n_ - 1; j >= 0; --j) {  // D z = y, then L^T x = z
    Eigen::Vector3d xj = d_inv_[j] * y_[j];
    for (int q = l_start_[j]; q < l_start_[j + 1]; ++q) xj.noalias() -= l_val_[q].transpose() * y_[l_row_[q]];
    y_[j] = xj;
  }
  for (int k = 0; k < n_; ++k) Eigen::Map<Eigen::Vector3d>(x + 3 * perm_[k]) = y_[k];
}

}  // namespace thinburn
