#pragma once
// Voigt notation of the statics: order xx, yy, zz, yz, xz, xy (Eq. 38); stresses are the symmetric
// parts of the (not necessarily symmetric) Love-Weber tensor, shear strains are engineering
// strains gamma = 2 eps, so that C_44 = G_yz (Eq. 39).
#include <Eigen/Core>

#include "core/Types.hpp"

namespace trueaniso {

namespace voigt {

constexpr int kRow[6] = {0, 1, 2, 1, 0, 0};
constexpr int kCol[6] = {0, 1, 2, 2, 2, 1};

// Symmetric part of a 3x3 tensor as a Voigt 6-vector.
inline Vec6 fromTensor(const Mat3& m) {
  Vec6 v;
  for (int I = 0; I < 6; ++I) v[I] = 0.5 * (m(kRow[I], kCol[I]) + m(kCol[I], kRow[I]));
  return v;
}

// Displacement gradient of a Voigt strain with engineering shears: E_yz = E_zy = e_4 / 2.
inline Mat3 gradient(const Vec6& e) {
  Mat3 E;
  E << e[0], 0.5 * e[5], 0.5 * e[4],
       0.5 * e[5], e[1], 0.5 * e[3],
       0.5 * e[4], 0.5 * e[3], e[2];
  return E;
}

// W(L) with E L = W e for every Voigt strain e: the affine displacement of a branch vector.
inline Eigen::Matrix<Real, 3, 6> branchMap(const Vec3& L) {
  Eigen::Matrix<Real, 3, 6> W = Eigen::Matrix<Real, 3, 6>::Zero();
  W(0, 0) = L.x();
  W(1, 1) = L.y();
  W(2, 2) = L.z();
  W(1, 3) = 0.5 * L.z(); W(2, 3) = 0.5 * L.y();
  W(0, 4) = 0.5 * L.z(); W(2, 4) = 0.5 * L.x();
  W(0, 5) = 0.5 * L.y(); W(1, 5) = 0.5 * L.x();
  return W;
}

}  // namespace voigt
}  // namespace trueaniso
