#include "statics/ZeroModes.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace trueaniso {

namespace {

// Position of entry (row, col) in a compressed column matrix, or -1.
long find(const Eigen::SparseMatrix<Real>& K, int row, int col) {
  const int* inner = K.innerIndexPtr();
  const int* b = inner + K.outerIndexPtr()[col];
  const int* e = inner + K.outerIndexPtr()[col + 1];
  const int* it = std::lower_bound(b, e, row);
  return (it != e && *it == row) ? it - inner : -1;
}

Real diagonal(const Eigen::SparseMatrix<Real>& K, int d) {
  const long p = find(K, d, d);
  return p >= 0 ? K.valuePtr()[p] : 0.0;
}

PinnedDof describe(const NetworkMatrix& net, int dof, const std::string& reason, Real ratio) {
  const int m = net.dofsPerBody;
  const int block = dof / m, local = dof % m;
  PinnedDof p;
  p.dof = dof;
  p.body = net.bodyOfBlock[block];
  const Vec6 v = net.frame[block].col(local);  // scaled motion [u, s theta]
  p.translation = v.head<3>();
  if (m == 6) p.rotation = v.tail<3>() / net.rotationScale[block];
  p.reason = reason;
  p.ratio = ratio;
  return p;
}

// K <- T^T K T, JE <- T^T JE, S <- S T for T = Q on block k's DOFs, identity elsewhere.
void turnBlock(NetworkMatrix& net, int k, const Eigen::MatrixXd& Q) {
  Eigen::SparseMatrix<Real>& K = net.K;
  const int m = net.dofsPerBody, d0 = k * m;
  const int* outer = K.outerIndexPtr();
  const int* inner = K.innerIndexPtr();
  Real* val = K.valuePtr();
  // Columns: the block's m columns share one row pattern (block structure).
  const long len = outer[d0 + 1] - outer[d0];
  Eigen::VectorXd row(m);
  for (long p = 0; p < len; ++p) {
    for (int a = 0; a < m; ++a) row[a] = val[outer[d0 + a] + p];
    const Eigen::VectorXd turned = Q.transpose() * row;  // the row vector times Q
    for (int a = 0; a < m; ++a) val[outer[d0 + a] + p] = turned[a];
  }
  // Rows: held by the columns of the neighbour blocks (the pattern is structurally symmetric:
  // they are the row blocks of the block's own column), m contiguous entries there.
  std::vector<int> neighbours;
  for (long p = outer[d0]; p < outer[d0 + 1]; ++p)
    if (inner[p] % m == 0) neighbours.push_back(inner[p] / m);
  for (int j : neighbours)
    for (int col = j * m; col < j * m + m; ++col) {
      const long p = find(K, d0, col);
      Eigen::Map<Eigen::VectorXd> v(val + p, m);
      v = Q.transpose() * Eigen::VectorXd(v);
    }
  net.JE.middleRows(d0, m) = Q.transpose() * net.JE.middleRows(d0, m);
  net.S.middleCols(d0, m) = net.S.middleCols(d0, m) * Q;
  net.frame[k].topLeftCorner(m, m) = net.frame[k].topLeftCorner(m, m) * Q;
}

}  // namespace

std::vector<PinnedDof> pinGlobalTranslation(const NetworkMatrix& net) {
  const int m = net.dofsPerBody, nblocks = static_cast<int>(net.bodyOfBlock.size());
  int best = 0;
  Real bestTrace = -1;
  for (int k = 0; k < nblocks; ++k) {
    if (!net.frame[k].isIdentity(0)) continue;  // its translations are no longer DOFs of their own
    const Real t = diagonal(net.K, k * m) + diagonal(net.K, k * m + 1) + diagonal(net.K, k * m + 2);
    if (t > bestTrace) { bestTrace = t; best = k; }
  }
  std::vector<PinnedDof> out;
  for (int a = 0; a < 3; ++a) out.push_back(describe(net, best * m + a, "global translation", 0.0));
  return out;
}

std::vector<PinnedDof> rotateLocalModes(NetworkMatrix& net, Real zeroTolerance, Real softTolerance) {
  std::vector<PinnedDof> out;
  const int m = net.dofsPerBody, nblocks = static_cast<int>(net.bodyOfBlock.size());
  for (int k = 0; k < nblocks; ++k) {
    Eigen::MatrixXd B(m, m);
    for (int i = 0; i < m; ++i)
      for (int j = 0; j < m; ++j) B(i, j) = 0.5 * (net.K.coeff(k * m + i, k * m + j) + net.K.coeff(k * m + j, k * m + i));
    const Real scale = B.trace() / m;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(B);
    const Eigen::VectorXd lambda = eig.eigenvalues();  // ascending
    if (!(lambda[0] < softTolerance * scale)) continue;
    turnBlock(net, k, eig.eigenvectors());
    for (int a = 0; a < m; ++a) net.localRatio[k * m + a] = lambda[a] / scale;
    for (int a = 0; a < m; ++a)
      if (lambda[a] < zeroTolerance * scale) out.push_back(describe(net, k * m + a, "local zero mode", lambda[a] / scale));
  }
  return out;
}

Eigen::SparseMatrix<Real> pinnedCopy(const Eigen::SparseMatrix<Real>& K, const std::vector<char>& pinned) {
  Eigen::SparseMatrix<Real> P = K;
  Real meanDiag = 0;
  for (int d = 0; d < K.cols(); ++d) meanDiag += std::abs(diagonal(K, d));
  meanDiag /= std::max<Eigen::Index>(1, K.cols());
  const int* outer = P.outerIndexPtr();
  const int* inner = P.innerIndexPtr();
  Real* val = P.valuePtr();
  for (int col = 0; col < P.cols(); ++col)
    for (int p = outer[col]; p < outer[col + 1]; ++p) {
      const int row = inner[p];
      if (!pinned[row] && !pinned[col]) continue;
      if (row != col) val[p] = 0.0;
      else if (val[p] <= 0) val[p] = meanDiag;
    }
  return P;
}

namespace {

// The softest unpinned local mode (localRatio < softTolerance) anywhere, else `dof`. Where the
// negative curvature of a hinge surfaces during the elimination depends on the ordering (it was
// seen at bodies that are not the hinge's neighbours), so the search is not restricted.
int softestLocalMode(const NetworkMatrix& net, const std::vector<char>& pinned, int dof, Real softTolerance) {
  int best = dof;
  Real bestRatio = softTolerance;
  for (int d = 0; d < static_cast<int>(pinned.size()); ++d)
    if (!pinned[d] && net.localRatio[d] < bestRatio) { best = d; bestRatio = net.localRatio[d]; }
  return best;
}

}  // namespace

Eigen::SparseMatrix<Real> pinnedSymmetricLower(const Eigen::SparseMatrix<Real>& K, const std::vector<char>& pinned) {
  const Eigen::SparseMatrix<Real> Kp = pinnedCopy(K, pinned);
  const Eigen::SparseMatrix<Real> Kt = Kp.transpose();
  const Eigen::SparseMatrix<Real> sym = 0.5 * (Kp + Kt);
  return sym.triangularView<Eigen::Lower>();
}

std::vector<PinnedDof> factorizeWithPins(SparseCholesky& chol, const NetworkMatrix& net, std::vector<char>& pinned,
                                         Real tolerance, Real softTolerance, int maxRounds, int* rounds) {
  std::vector<PinnedDof> out;
  for (int round = 1;; ++round) {
    if (rounds) *rounds = round;
    if (round > maxRounds) {
      std::ostringstream msg;
      msg << "the contact network is not a solid: " << out.size() << " zero or negative pivots pinned in "
          << maxRounds << " factorisations and more remain (a mechanism, or an unstable held state)";
      throw InputError(msg.str());
    }
    const Eigen::SparseMatrix<Real> lower = pinnedSymmetricLower(net.K, pinned);
    const int failed = chol.factorize(lower);
    if (failed >= 0) {
      // A negative curvature from a soft local mode (a hinge held by initial forces only) can
      // surface at another DOF's pivot: pin the softest unpinned local mode if there is one, the
      // failing DOF itself otherwise.
      const int pin = softestLocalMode(net, pinned, failed, softTolerance);
      pinned[pin] = 1;
      const Real ratio = std::isfinite(net.localRatio[pin]) ? net.localRatio[pin] : std::numeric_limits<Real>::quiet_NaN();
      out.push_back(describe(net, pin, "non-positive pivot", ratio));
      continue;
    }
    const Eigen::VectorXd d = chol.pivots();
    int added = 0;
    for (int k = 0; k < d.size(); ++k) {
      if (pinned[k]) continue;
      const Real ratio = d[k] / diagonal(lower, k);
      if (ratio < tolerance) {
        pinned[k] = 1;
        out.push_back(describe(net, k, "zero pivot", ratio));
        ++added;
      }
    }
    if (added == 0) return out;
  }
}

}  // namespace trueaniso
