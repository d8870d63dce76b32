#pragma once
// Directional elastic constants of a 6x6 stiffness (Eqs. 38-42): the one place every route to a
// 6x6 (micromechanical prediction, exact statics, the Python analysis) takes E_i, nu_ij, G_ij from.
//
// E_i and nu_ij are those of a probe on axis i whose cell keeps its shear strains at zero and holds
// the two other normal stresses: the normal 3x3 block is inverted as it is. For a symmetric block
// this is Eqs. (40)-(42) (their cofactor closed forms, tested against it); with an anisotropic
// prestress the Cauchy-stress tangent is not symmetric (C_12 != C_21), and the closed forms,
// which assume symmetry, would then differ from the probe.
#include "core/Types.hpp"

namespace trueaniso {

struct OrthotropicModuli {
  Vec3 E = Vec3::Zero();  // E_x, E_y, E_z, Eq. (40)
  // nu(i, j) = nu_ij with i the loading and j the lateral direction, as Eq. (11); NaN on the
  // diagonal. nu_ij = -S_ji / S_ii of S = (normal block)^-1.
  Mat3 nu = Mat3::Zero();
  Vec3 G = Vec3::Zero();  // G_yz = C_44, G_xz = C_55, G_xy = C_66, Eq. (39)
  Real Delta = 0;         // Eq. (41): determinant of the normal 3x3 block
};

// Entries outside the normal block and the shear diagonal are ignored (the orthotropic pattern
// of Eq. 38). The printed Eq. (42) has two misprints in its last line (docs/fabric.md).
OrthotropicModuli orthotropicModuli(const Mat6& C);

}  // namespace trueaniso
