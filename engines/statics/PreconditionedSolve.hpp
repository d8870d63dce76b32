#pragma once
// K u = f for the (slightly non-symmetric) network tangent, preconditioned by the Cholesky factor
// of its symmetric part. Iterative refinement first (u += M^-1 (f - K u): converges when the
// non-symmetric part is small against the smallest stiffness, two or three iterations on every
// specimen tried); if it stalls, right-preconditioned restarted GMRES per column, which also
// copes with a few eigenvalues of M^-1 K far from 1.
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "statics/SparseCholesky.hpp"
#include "statics/Voigt.hpp"

namespace trueaniso {

struct SolveReport {
  int refinements = 0;   // refinement iterations (each one solve with the factor)
  int gmresIterations = 0;  // GMRES iterations over all columns (0: not needed)
  Real residual = 0;     // max_J ||f_J - K u_J|| / scale_J
};

// `scale` normalises each column's residual. skipRefinement forces GMRES (for tests).
Eigen::MatrixXd preconditionedSolve(const Eigen::SparseMatrix<Real>& K, const SparseCholesky& M,
                                    const Eigen::MatrixXd& f, const Vec6& scale, Real tolerance, int maxIterations,
                                    SolveReport* report, bool skipRefinement = false);

}  // namespace trueaniso
