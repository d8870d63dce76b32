#pragma once
// Sparse Cholesky factorisation by SuiteSparse CHOLMOD (supernodal with BLAS when it pays, fill-
// reducing ordering by AMD/METIS), called through its C API rather than Eigen's CholmodSupport
// wrapper because the statics needs what the wrapper hides: the column at which a factorisation
// stopped (a pivot that is not positive) and the pivots themselves (zero-mode detection), and a
// numeric refactorisation on the same symbolic analysis after DOFs are pinned.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

#include "core/Types.hpp"

namespace trueaniso {

class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  // `lower`: the lower triangle (diagonal included) of a symmetric matrix, compressed column
  // storage. analyze() orders and analyses its pattern; factorize() (which analyses first if
  // needed) may then be called for any matrix of that pattern. factorize() returns -1 on success,
  // else the row/column (original numbering) whose pivot was not positive.
  void analyze(const Eigen::SparseMatrix<Real>& lower);
  int factorize(const Eigen::SparseMatrix<Real>& lower);
  // Pivot d_k = L_kk^2 of every row/column (original numbering); valid after a success.
  Eigen::VectorXd pivots() const;
  Eigen::MatrixXd solve(const Eigen::MatrixXd& rhs) const;

  long factorNonzeros() const;
  bool supernodal() const;
  double flops() const;  // of one factorisation, from the analysis

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace trueaniso
