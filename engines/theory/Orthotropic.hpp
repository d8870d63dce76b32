#pragma once
// Directional elastic constants of a 6x6 stiffness (Eqs. 38-42): the one place every route to a
// 6x6 (micromechanical prediction, exact statics, the Python analysis) takes E_i, nu_ij, G_ij from.
//
// Definition: the constants a stress probe measures, the probe holding every stress but the
// probed one (the five others at the state's values: the two other normal stresses, and the shear
// stresses at zero, as the paper's frictionless walls hold them; control/StressProbe). Its strains
// are those of the compliance S = C^-1 of the whole 6x6: E_i = 1/S_ii (Eq. 10), nu_ij =
// -S_ji/S_ii (Eq. 11), G_ij = 1/S_kk (k = 4, 5, 6 for yz, xz, xy).
//
// For an orthotropic C in the cell's axes (no normal-shear or shear-shear coupling) these are
// Eqs. (39)-(42): S's normal block is the inverse of C's, G_ij = C_kk, and for a symmetric block
// the printed cofactor forms follow (tested). A random packing's C has small couplings; then
// inverting only the normal block would give the probe of an orthorhombic cell, whose shear
// strains are held at zero while its shear stresses go where they will (our cell before it could
// shear), and C_44 would be the shear probe with every strain but gamma_yz held. With the full
// cell the shear stresses are held instead, so the full inverse is what a probe measures.
// (With an anisotropic prestress the Cauchy-stress tangent is not symmetric, C_12 != C_21: the
// inversion takes C as it is.)
#include "core/Types.hpp"

namespace trueaniso {

struct OrthotropicModuli {
  Vec3 E = Vec3::Zero();  // E_x, E_y, E_z, Eq. (40): 1/S_ii
  // nu(i, j) = nu_ij with i the loading and j the lateral direction, as Eq. (11); NaN on the
  // diagonal. nu_ij = -S_ji / S_ii.
  Mat3 nu = Mat3::Zero();
  Vec3 G = Vec3::Zero();  // G_yz, G_xz, G_xy: 1/S_44, 1/S_55, 1/S_66 (C_44, C_55, C_66 when orthotropic, Eq. 39)
  Real Delta = 0;         // Eq. (41): determinant of the normal 3x3 block of C
};

// A singular block gives non-finite moduli (a C without shear block: G is, E_i and nu_ij of an
// uncoupled C are not). The printed Eq. (42) has two misprints in its last line
// (docs/fabric.md).
OrthotropicModuli orthotropicModuli(const Mat6& C);

}  // namespace trueaniso
