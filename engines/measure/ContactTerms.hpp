#pragma once
// One contact's terms of the cell measures that a controller reads (measure/Stress.hpp), apart
// from any contact container: our scene's passes and the YADE plugin's engines, which walk YADE's
// interactions, add the same terms.
#include "core/Types.hpp"
#include "core/Voigt.hpp"

namespace trueaniso {

// Love-Weber: F (x) L, F the force on body 2, L the branch from body 1 to body 2.
inline void addStressTerm(const Vec3& F, const Vec3& L, Mat3& acc) { acc.noalias() += F * L.transpose(); }

// The diagonal of Eq. (32), contact springs only, of a contact of normal stiffness kn (0: none, all
// six terms zero) and k_s = ratio k_n, unit normal n and branch L, in Voigt order:
//  - K_kk = L_k^2 [k_s + (k_n - k_s) n_k^2], the kk kk component of Eq. (32);
//  - engineering shear gamma_ij: the affine displacement u = (gamma/2)(L_j e_i + L_i e_j), the force
//    k_s u + (k_n - k_s) n (n.u), the stress sym(dF (x) L)_ij: the ij ij component of Eq. (32)
//    symmetrised over (ij) and (kl), as the static solve's affine part. With
//    nu = (n_i L_j + n_j L_i) / 2 it is k_s (L_i^2 + L_j^2) / 4 + (k_n - k_s) nu^2.
// On scalars (T = Real), or on several contacts side by side (T a vector of them, one contact a
// lane: measure/CellLanes.hpp), each contact's arithmetic the same.
template <class T>
__attribute__((always_inline)) inline void affineStiffnessTerms(const T& kn, Real ratio, const T& nx, const T& ny,
                                                                const T& nz, const T& Lx, const T& Ly, const T& Lz,
                                                                T* k) {
  const T ks = ratio * kn, kd = (1.0 - ratio) * kn, quarter = 0.25 * ks;
  const T xx = Lx * Lx, yy = Ly * Ly, zz = Lz * Lz;
  k[0] = xx * (ks + kd * nx * nx);
  k[1] = yy * (ks + kd * ny * ny);
  k[2] = zz * (ks + kd * nz * nz);
  const T yz = 0.5 * (ny * Lz + nz * Ly), xz = 0.5 * (nx * Lz + nz * Lx), xy = 0.5 * (nx * Ly + ny * Lx);
  k[3] = quarter * (yy + zz) + kd * yz * yz;
  k[4] = quarter * (xx + zz) + kd * xz * xz;
  k[5] = quarter * (xx + yy) + kd * xy * xy;
}

// The same terms added to acc, for a contact with kn > 0.
inline void addAffineStiffnessTerm(Real kn, Real ratio, const Vec3& n, const Vec3& L, Vec6& acc) {
  Real k[6];
  affineStiffnessTerms<Real>(kn, ratio, n.x(), n.y(), n.z(), L.x(), L.y(), L.z(), k);
  for (int I = 0; I < 6; ++I) acc[I] += k[I];
}

}  // namespace trueaniso
