#pragma once
// One contact's terms of the cell measures that a controller reads (measure/Stress.hpp), apart
// from any contact container: our scene's passes and the YADE plugin's engines, which walk YADE's
// interactions, add the same terms.
#include "core/Types.hpp"
#include "core/Voigt.hpp"

namespace trueaniso {

// Love-Weber: F (x) L, F the force on body 2, L the branch from body 1 to body 2.
inline void addStressTerm(const Vec3& F, const Vec3& L, Mat3& acc) { acc.noalias() += F * L.transpose(); }

// The diagonal of Eq. (32), contact springs only, of a contact of normal stiffness kn > 0 and
// k_s = ratio k_n, unit normal n and branch L.
inline void addAffineStiffnessTerm(Real kn, Real ratio, const Vec3& n, const Vec3& L, Vec6& acc) {
  const Real ks = ratio * kn, kd = (1.0 - ratio) * kn;  // k_n - k_s
  for (int k = 0; k < 3; ++k) {
    // K_kk = sum L_k^2 [k_s + (k_n - k_s) n_k^2], the kk kk component of Eq. (32).
    acc[k] += L[k] * L[k] * (ks + kd * n[k] * n[k]);
  }
  for (int I = 3; I < 6; ++I) {
    // Engineering shear gamma_ij: the affine displacement u = (gamma/2)(L_j e_i + L_i e_j), the
    // force k_s u + (k_n - k_s) n (n.u), the stress sym(dF (x) L)_ij: the ij ij component of
    // Eq. (32) symmetrised over (ij) and (kl), as the static solve's affine part.
    const int i = voigt::kRow[I], j = voigt::kCol[I];
    const Real nu = 0.5 * (n[i] * L[j] + n[j] * L[i]);
    const Real dFi = 0.5 * ks * L[j] + kd * n[i] * nu, dFj = 0.5 * ks * L[i] + kd * n[j] * nu;
    acc[I] += 0.5 * (dFi * L[j] + dFj * L[i]);
  }
}

}  // namespace trueaniso
