#pragma once
// Directional elastic constants of an orthotropic stiffness matrix (Eqs. 38-42): the step shared
// by every route to a 6x6 stiffness (micromechanical prediction, probes, exact statics).
#include <Eigen/Core>

#include "core/Types.hpp"

namespace trueaniso {

// Voigt order of Eq. (38): 1..6 = xx, yy, zz, yz, xz, xy.
using Mat6 = Eigen::Matrix<Real, 6, 6>;

struct OrthotropicModuli {
  Vec3 E = Vec3::Zero();  // E_x, E_y, E_z, Eq. (40)
  // nu(i, j) = nu_ij with i the loading and j the lateral direction, as Eq. (11); NaN on the
  // diagonal. Equal to -S_ji / S_ii of the compliance S = C^-1.
  Mat3 nu = Mat3::Zero();
  Vec3 G = Vec3::Zero();  // G_yz, G_xz, G_xy, Eq. (39)
  Real Delta = 0;         // Eq. (41): determinant of the normal 3x3 block
};

// Uses C11..C33, C12, C13, C23, C44, C55, C66 only (the orthotropic pattern of Eq. 38); any other
// entry is ignored. The Poisson's ratios are the closed forms of the cofactors of the normal
// block; the printed Eq. (42) has two misprints in its last line (see docs/fabric.md).
OrthotropicModuli orthotropicModuli(const Mat6& C);

}  // namespace trueaniso
