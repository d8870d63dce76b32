#include "core/Cell.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <unsupported/Eigen/MatrixFunctions>

namespace trueaniso {

namespace {

// |det| relative to the product of the column lengths: 1 for orthogonal vectors, 0 for coplanar.
Real skewness(const Mat3& h) {
  const Real norms = h.col(0).norm() * h.col(1).norm() * h.col(2).norm();
  return norms > 0 ? h.determinant() / norms : 0.0;
}

// The size-reduction coefficient of column j on column i: a_j . a_i / |a_i|^2.
Real reductionCoefficient(const Mat3& h, int i, int j) { return h.col(j).dot(h.col(i)) / h.col(i).squaredNorm(); }

// Pairwise size reduction of the columns of h: a_j -= k a_i, k = round(mu), while |mu| > 1/2, with
// mu = reductionCoefficient(h, i, j); step(i, j, k) is told of every step. Each step shortens a_j strictly
// (by |a_i|^2 k (2 mu - k) > 0), and the lattice has finitely many shorter vectors, so this ends;
// the cap is a guard against round-off only. h ends as another basis of the same lattice.
template <class Step>
void sizeReduce(Mat3& h, Step&& step) {
  for (int iter = 0; iter < 100; ++iter) {
    bool changed = false;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        if (i == j) continue;
        const Real mu = reductionCoefficient(h, i, j);
        if (!(std::abs(mu) > 0.5 + 1e-9)) continue;
        const Real k = std::round(mu);
        h.col(j) -= k * h.col(i);
        step(i, j, k);
        changed = true;
      }
    if (!changed) break;
  }
}

void requireCellMatrix(const Mat3& h, const char* name, Real skew) {
  std::ostringstream m;
  if (!h.allFinite()) m << "the cell matrix " << name << " has non-finite entries";
  else if (skew < 0)
    m << "the cell matrix " << name << " is inverted (det = " << h.determinant()
      << " < 0: its columns, the cell vectors, must form a right-handed set)";
  else if (skew < 1e-6)
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
  requireCellMatrix(hSize, "hSize", skewness(hSize));
  // The reference cell is judged by its lattice, then by the round-off of F. Every flip maps
  // refHSize by the flip's M, as it maps hSize, so that F = hSize refHSize^-1 is the motion alone;
  // unlike hSize it is never reduced back, so its vectors skew as the product of the flips grows
  // (simple shears of 1 alternating between the xz and zx planes, 15 in all: skewness 5e-7).
  // Those vectors still span the reference cell's lattice, and a size-reduced basis of it, the
  // same after any flips, says whether the reference is degenerate. What the skew of the vectors
  // themselves costs is accuracy: F's relative round-off grows as eps / skewness (measured 0.07-0.8
  // of it down to skewness 1e-16), so below 1e-9 F, every strain and the servo's strain guard would
  // carry up to 2e-7 of round-off and more.
  Mat3 reduced = refHSize;
  if (refHSize.allFinite()) sizeReduce(reduced, [](int, int, Real) {});
  requireCellMatrix(refHSize, "refHSize", skewness(reduced));
  const Real skew = skewness(refHSize);
  if (skew < 1e-9) {
    std::ostringstream m;
    m << "the cell matrix refHSize has vectors so skewed (det / |a_1||a_2||a_3| = " << skew
      << ", as many cell flips leave them; a reduced basis of their lattice has " << skewness(reduced)
      << ") that the deformation gradient "
      << "hSize refHSize^-1 would carry a relative round-off of "
      << std::numeric_limits<Real>::epsilon() / skew
      << "; take the present cell as the reference (refHSize = hSize, in Python Scene.cell_ref = Scene.cell) to go on";
    throw InputError(m.str());
  }
  require(velGrad.allFinite(), "the cell's velocity gradient has non-finite entries");
}

Mat3i Cell::reduction(Real threshold) const {
  Mat3 h = hSize;
  bool needed = false;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j && std::abs(reductionCoefficient(h, i, j)) > threshold) needed = true;
  Mat3i M = Mat3i::Identity();
  if (!needed) return M;
  // A flip's entries are ints: a multiple beyond their range (a cell some 1e9 times longer along
  // one vector than across it) is refused rather than cast, which would be undefined.
  sizeReduce(h, [&](int i, int j, Real k) {
    if (!(std::abs(k) <= 1 << 30)) {
      std::ostringstream m;
      m << "the cell's vectors are too unequal to flip: vector " << j + 1 << " is " << k << " times vector " << i + 1
        << " along it, past what a flip's whole numbers hold";
      throw InputError(m.str());
    }
    M.col(j) -= static_cast<int>(k) * M.col(i);
  });
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
