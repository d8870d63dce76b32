#pragma once
// Engineering constants of a 6x6 Voigt stiffness (compression-positive stress and strain).
// E_i and nu_ij follow Eqs. (40)-(42): they invert the normal 3x3 block only, i.e. they are the
// moduli of a probe whose cell keeps its shear strains at zero (the orthorhombic cell of the
// probe cannot shear) and holds the two other normal stresses. The block is inverted as it is:
// with an anisotropic prestress the Cauchy-stress tangent is not symmetric (C_12 != C_21), and
// Eq. (40)'s symmetric closed forms would then differ from the probe.
#include <limits>

#include "statics/Voigt.hpp"

namespace trueaniso {

struct ElasticConstants {
  Vec3 E = Vec3::Zero();   // E_x, E_y, E_z (Eq. 40)
  Mat3 nu = Mat3::Zero();  // nu(i, j) = nu_ij = -S_ji / S_ii, i loading, j lateral (Eq. 42); NaN on i = j
  Vec3 G = Vec3::Zero();   // G_yz = C_44, G_xz = C_55, G_xy = C_66 (Eq. 39)
};

inline ElasticConstants elasticConstants(const Mat6& C) {
  ElasticConstants k;
  const Mat3 S = C.topLeftCorner<3, 3>().inverse();
  for (int i = 0; i < 3; ++i) {
    k.E[i] = 1.0 / S(i, i);
    for (int j = 0; j < 3; ++j) k.nu(i, j) = i == j ? std::numeric_limits<Real>::quiet_NaN() : -S(j, i) / S(i, i);
    k.G[i] = C(3 + i, 3 + i);
  }
  return k;
}

}  // namespace trueaniso
