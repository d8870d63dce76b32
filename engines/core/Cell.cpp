#include "core/Cell.hpp"

#include <cmath>
#include <sstream>
#include <unsupported/Eigen/MatrixFunctions>

namespace trueaniso {

namespace {

// |det| relative to the product of the column lengths: 1 for orthogonal vectors, 0 for coplanar.
Real skewness(const Mat3& h) {
  const Real norms = h.col(0).norm() * h.col(1).norm() * h.col(2).norm();
  return norms > 0 ? h.determinant() / norms : 0.0;
}

void requireCellMatrix(const Mat3& h, const char* name) {
  std::ostringstream m;
  if (!h.allFinite()) m << "the cell matrix " << name << " has non-finite entries";
  else if (skewness(h) < 0)
    m << "the cell matrix " << name << " is inverted (det = " << h.determinant()
      << " < 0: its columns, the cell vectors, must form a right-handed set)";
  else if (skewness(h) < 1e-6)
    m << "the cell matrix " << name << " is singular (det = " << h.determinant()
      << ": its columns, the cell vectors, are coplanar or zero)";
  if (!m.str().empty()) throw InputError(m.str());
}

}  // namespace

Vec6 Cell::strain() const { return strainBetween(Mat3::Identity(), deformation()); }

Vec3 Cell::widths() const {
  const Real V = volume();
  Vec3 w;
  for (int k = 0; k < 3; ++k) w[k] = V / hSize.col((k + 1) % 3).cross(hSize.col((k + 2) % 3)).norm();
  return w;
}

void Cell::validate() const {
  requireCellMatrix(hSize, "hSize");
  requireCellMatrix(refHSize, "refHSize");
  require(velGrad.allFinite(), "the cell's velocity gradient has non-finite entries");
}

Mat3i Cell::reduction(Real threshold) const {
  Mat3 h = hSize;
  auto coefficient = [&](int i, int j) { return h.col(j).dot(h.col(i)) / h.col(i).squaredNorm(); };
  bool needed = false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j && std::abs(coefficient(i, j)) > threshold) needed = true;
  Mat3i M = Mat3i::Identity();
  if (!needed) return M;
  // Pairwise size reduction: a_j -= round(mu) a_i while |mu| > 1/2. Each step shortens a_j
  // strictly (by |a_i|^2 k (2 mu - k) > 0), and the lattice has finitely many shorter vectors,
  // so this ends; the cap is a guard against round-off only.
  for (int iter = 0; iter < 100; ++iter) {
    bool changed = false;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        if (i == j) continue;
        const Real mu = coefficient(i, j);
        if (std::abs(mu) <= 0.5 + 1e-9) continue;
        const int k = static_cast<int>(std::lround(mu));
        h.col(j) -= k * h.col(i);
        M.col(j) -= k * M.col(i);
        changed = true;
      }
    if (!changed) break;
  }
  return M;
}

void Cell::flip(const Mat3i& M) {
  require(M.determinant() == 1, "a cell flip must be an integer matrix of determinant 1");
  const Mat3 m = M.cast<Real>();
  hSize = hSize * m;
  refHSize = refHSize * m;
}

Vec6 strainBetween(const Mat3& F0, const Mat3& F1) {
  if (Cell::isDiagonal(F0) && Cell::isDiagonal(F1)) {
    Vec6 e = Vec6::Zero();
    for (int k = 0; k < 3; ++k) e[k] = -std::log(F1(k, k) / F0(k, k));
    return e;
  }
  const Mat3 X = F1 * F0.inverse();
  const Mat3 logX = X.log();
  return -voigt::strainOf(0.5 * (logX + logX.transpose()));
}

Mat3i unimodularInverse(const Mat3i& M) {
  const int det = M.determinant();
  require(det == 1 || det == -1, "not a unimodular integer matrix");
  Mat3i adj;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
      adj(i, j) = M(r0, c0) * M(r1, c1) - M(r0, c1) * M(r1, c0);
    }
  return det * adj;
}

}  // namespace trueaniso
