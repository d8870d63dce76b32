#pragma once
// Micromechanical stiffness of the kinematic hypothesis written with the fabric tensors B and M
// (Eqs. 35 and 37), its orthotropic Voigt matrix (Appendix A, A1-A9) and the directional
// moduli that follow (Eqs. 39-42).
#include "core/Material.hpp"
#include "measure/Fabric.hpp"
#include "theory/Orthotropic.hpp"

namespace trueaniso {

// The rotation factor zeta of Eq. (37), k_s* = zeta k_s (section 4.2): its one valid range, used
// by the prediction, the static derivation (statics/RotationFactor) and the Python fits
// (engines.ZETA_RANGE).
//  - zeta >= 0: a negative tangential stiffness has no meaning (the directional form
//    sqrt(zeta_i zeta_k) of pyscripts/trueaniso/zeta.py needs it too);
//  - zeta <= 5: the paper's zeta is a reduction (<= 1), but a fit or a derivation can land above
//    1 (rotations blocked give 1.01) and is reported as it is, not clipped; 5 is far beyond any
//    value met and keeps the root searches bounded.
struct ZetaRange {
  static constexpr Real lo = 0.0, hi = 5.0;
};
void requireZeta(Real zeta);

// Which Nc/V enters Eq. (37): Eq. (36) as the paper does, or the counted Nc / V.
enum class ContactDensity { Eq36, Count };

// Eq. (37): C_ijkl = (Nc/V) [C_s* B_ik delta_jl + (C_n - C_s*) M_ijkl] with C_s* = zeta C_s;
// zeta = 1 is Eq. (35). Stored as Mat9: row 3i+j, column 3k+l.
Mat9 stiffnessTensor(const Mat3& B, const Mat9& M, Real contactDensity, Real Cn, Real Cs, Real zeta);

// Appendix A: C11 = C_1111, ..., C12 = (C_1122 + C_2211)/2, ..., C44 = (C_2323 + C_3232)/2,
// C55 = (C_1313 + C_3131)/2, C66 = (C_1212 + C_2121)/2, zero elsewhere (Eq. 38).
Mat6 orthotropicStiffness(const Mat9& C);

struct MicromechanicalPrediction {
  Real zeta = 1;
  Real contactDensity = 0;  // the Nc/V used
  Mat9 C = Mat9::Zero();    // Eq. (37)
  Mat6 voigt = Mat6::Zero();  // Appendix A
  OrthotropicModuli moduli;   // Eqs. (39)-(42)
};

// Eq. (37), Appendix A and Eqs. (39)-(42) from given fabric tensors, Nc/V, C_n and C_s; zeta
// outside ZetaRange is refused.
MicromechanicalPrediction predict(const Mat3& B, const Mat9& M, Real contactDensity, Real Cn, Real Cs, Real zeta);
// The same from a scene's fabric and material.
MicromechanicalPrediction predict(const Fabric& fabric, const Material& material, Real zeta = 1.0,
                                  ContactDensity density = ContactDensity::Eq36);

}  // namespace trueaniso
