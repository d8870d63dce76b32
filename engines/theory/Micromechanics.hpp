#pragma once
// Micromechanical stiffness of the kinematic hypothesis written with the fabric tensors B and M
// (Eqs. 35 and 37), its orthotropic Voigt matrix (Appendix A, A1-A9) and the directional
// moduli that follow (Eqs. 39-42).
#include "core/Material.hpp"
#include "measure/Fabric.hpp"
#include "theory/Orthotropic.hpp"

namespace trueaniso {

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

// zeta in [0, 1] as the paper defines it (k_s* = zeta k_s); anything else is refused.
MicromechanicalPrediction predict(const Fabric& fabric, const Material& material, Real zeta = 1.0,
                                  ContactDensity density = ContactDensity::Eq36);

}  // namespace trueaniso
