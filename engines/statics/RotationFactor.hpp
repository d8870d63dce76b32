#pragma once
// The rotation factor zeta of Section 4.2 derived from static solves instead of fitted to probes.
//
// Eq. (37) splits the kinematic stiffness into a normal and a tangential part,
//   C(zeta) = N_c/V [zeta C_s B d + (C_n - zeta C_s) M] = A_n + zeta A_s,
// A_n = (1/V) sum k_n L n L n and A_s = (1/V) sum k_s (L L d - L n L n) (both as Voigt matrices of
// the contacts of the held state, zeta = 1 giving Eq. 32). E_i(zeta) follows from C(zeta) by
// Eq. (40). Two factors are derived, per axis and for the paper's pair (h = x, y; v = z):
//  - zeta ("magnitude"): E_i(zeta_i) = E_i of the relaxed static solve with rotations free (it
//    lumps the translational non-affinity in too, and depends on the N_c/V choice). The paper
//    fits zeta on the directional contrast a_i^2 of Eq. (25) instead, which does not:
//    pyscripts/trueaniso/zeta.py, docs/statics.md section 7.1;
//  - zetaRotation ("rotation alone"): E_i(zeta)/E_i(1) = E_i(rotations free)/E_i(rotations
//    blocked), i.e. the reduction that freeing the rotations adds to the relaxed, rotation-
//    blocked solve, expressed as a tangential-stiffness factor on the kinematic estimate.
// zeta_h solves the same equations for (E_x + E_y)/2; zeta_v is the z one. A factor whose
// equation has no root in ZetaRange (theory/Micromechanics.hpp) is NaN.
#include "statics/Voigt.hpp"

namespace trueaniso {

struct RotationFactor {
  Vec3 zeta = Vec3::Zero();
  Real zetaH = 0, zetaV = 0;
  Vec3 zetaRotation = Vec3::Zero();
  Real zetaRotationH = 0, zetaRotationV = 0;
};

// Young's moduli of Eq. (40) from A_n + zeta A_s.
Vec3 kinematicModuli(const Mat6& normalPart, const Mat6& shearPart, Real zeta);

RotationFactor rotationFactor(const Mat6& normalPart, const Mat6& shearPart, const Vec3& relaxedFree,
                              const Vec3& relaxedBlocked);

}  // namespace trueaniso
