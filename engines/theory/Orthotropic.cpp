#include "theory/Orthotropic.hpp"

#include <limits>

namespace trueaniso {

OrthotropicModuli orthotropicModuli(const Mat6& C) {
  const Real c11 = C(0, 0), c22 = C(1, 1), c33 = C(2, 2);
  const Real c12 = C(0, 1), c13 = C(0, 2), c23 = C(1, 2);
  OrthotropicModuli m;
  m.Delta = c11 * c22 * c33 + 2.0 * c12 * c13 * c23 - c11 * c23 * c23 - c22 * c13 * c13 -
            c33 * c12 * c12;
  // Cofactors of the normal block: S_ii = A_ii / Delta and S_ji = A_ji / Delta, so that
  // E_i = 1/S_ii = Delta/A_ii and nu_ij = -S_ji/S_ii = -A_ji/A_ii.
  const Real a11 = c22 * c33 - c23 * c23;
  const Real a22 = c11 * c33 - c13 * c13;
  const Real a33 = c11 * c22 - c12 * c12;
  const Real m12 = c12 * c33 - c13 * c23;  // = -A_12
  const Real m13 = c13 * c22 - c12 * c23;  // = -A_13
  const Real m23 = c23 * c11 - c12 * c13;  // = -A_23
  m.E = Vec3(m.Delta / a11, m.Delta / a22, m.Delta / a33);
  m.nu(0, 1) = m12 / a11;  // nu_xy
  m.nu(0, 2) = m13 / a11;  // nu_xz
  m.nu(1, 0) = m12 / a22;  // nu_yx
  m.nu(1, 2) = m23 / a22;  // nu_yz
  m.nu(2, 0) = m13 / a33;  // nu_zx
  m.nu(2, 1) = m23 / a33;  // nu_zy (printed as "nu_xy = (C23 C11 - C12 C23)/..." in Eq. 42)
  for (int i = 0; i < 3; ++i) m.nu(i, i) = std::numeric_limits<Real>::quiet_NaN();
  m.G = Vec3(C(3, 3), C(4, 4), C(5, 5));
  return m;
}

}  // namespace trueaniso
