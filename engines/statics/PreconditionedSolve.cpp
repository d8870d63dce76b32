#include "statics/PreconditionedSolve.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace trueaniso {

namespace {

Real worst(const Eigen::MatrixXd& r, const Vec6& scale) {
  Real w = 0;
  for (int J = 0; J < r.cols(); ++J) w = std::max(w, r.col(J).norm() / scale[J]);
  return w;
}

// GMRES(restart) on K M^-1 y = f, u = M^-1 y, starting from u0; returns iterations used.
int gmres(const Eigen::SparseMatrix<Real>& K, const SparseCholesky& M, const Eigen::VectorXd& f,
          Eigen::VectorXd& u, Real target, int maxIterations, int restart = 60) {
  const int n = static_cast<int>(f.size());
  int used = 0;
  while (used < maxIterations) {
    Eigen::VectorXd r = f - K * u;
    const Real beta = r.norm();
    if (beta <= target) break;
    Eigen::MatrixXd V(n, restart + 1), Z(n, restart);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(restart + 1, restart);
    V.col(0) = r / beta;
    int k = 0;
    Eigen::VectorXd y;
    for (; k < restart && used < maxIterations; ++k, ++used) {
      Z.col(k) = M.solve(V.col(k));
      Eigen::VectorXd w = K * Z.col(k);
      for (int i = 0; i <= k; ++i) {  // modified Gram-Schmidt
        H(i, k) = V.col(i).dot(w);
        w -= H(i, k) * V.col(i);
      }
      H(k + 1, k) = w.norm();
      if (H(k + 1, k) > 0) V.col(k + 1) = w / H(k + 1, k);
      // Least squares min ||beta e1 - H y|| on the (k+2) x (k+1) Hessenberg matrix.
      Eigen::VectorXd rhs = Eigen::VectorXd::Zero(k + 2);
      rhs[0] = beta;
      const Eigen::MatrixXd Hk = H.topLeftCorner(k + 2, k + 1);
      y = Hk.colPivHouseholderQr().solve(rhs);
      if ((rhs - Hk * y).norm() <= target || H(k + 1, k) == 0) { ++k; ++used; break; }
    }
    u += Z.leftCols(k) * y.head(k);
  }
  return used;
}

}  // namespace

Eigen::MatrixXd preconditionedSolve(const Eigen::SparseMatrix<Real>& K, const SparseCholesky& M,
                                    const Eigen::MatrixXd& f, const Vec6& scale, Real tolerance, int maxIterations,
                                    SolveReport* report, bool skipRefinement) {
  SolveReport rep;
  Eigen::MatrixXd u = M.solve(f);
  Eigen::MatrixXd r = f - K * u;
  Real rel = worst(r, scale), best = rel;
  int stalled = 0;
  while (!skipRefinement && rel > tolerance && rep.refinements < maxIterations && stalled < 3) {
    u += M.solve(r);
    r = f - K * u;
    rel = worst(r, scale);
    ++rep.refinements;
    if (rel < 0.5 * best) { best = rel; stalled = 0; } else { ++stalled; }
  }
  if (rel > tolerance) {
    if (!(rel <= best)) u = M.solve(f);  // refinement diverged: restart from the first solve
    for (int J = 0; J < f.cols(); ++J) {
      Eigen::VectorXd uj = u.col(J);
      rep.gmresIterations += gmres(K, M, f.col(J), uj, tolerance * scale[J], maxIterations);
      u.col(J) = uj;
    }
    r = f - K * u;
    rel = worst(r, scale);
  }
  rep.residual = rel;
  if (report) *report = rep;
  return u;
}

}  // namespace trueaniso
