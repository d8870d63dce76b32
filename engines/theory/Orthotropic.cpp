#include "theory/Orthotropic.hpp"

#include <Eigen/LU>
#include <limits>

namespace trueaniso {

OrthotropicModuli orthotropicModuli(const Mat6& C) {
  constexpr Real nan = std::numeric_limits<Real>::quiet_NaN();
  OrthotropicModuli m;
  const Mat3 Cnn = C.topLeftCorner<3, 3>(), Cns = C.topRightCorner<3, 3>();
  const Mat3 Csn = C.bottomLeftCorner<3, 3>(), Css = C.bottomRightCorner<3, 3>();
  m.Delta = Cnn.determinant();
  // The normal and shear blocks of S = C^-1 by their Schur complements. Without normal-shear
  // coupling (an orthotropic C, e.g. Appendix A's) they are the inverses of C's own blocks: E_i and
  // nu_ij then need the normal block only, as Eq. (40) does, even where no shear block is given.
  const bool coupled = !Cns.isZero(0) || !Csn.isZero(0);
  const Mat3 Snn = coupled ? Mat3((Cnn - Cns * Css.inverse() * Csn).inverse()) : Mat3(Cnn.inverse());
  const Mat3 Sss = coupled ? Mat3((Css - Csn * Cnn.inverse() * Cns).inverse()) : Mat3(Css.inverse());
  for (int i = 0; i < 3; ++i) {
    m.E[i] = 1.0 / Snn(i, i);
    for (int j = 0; j < 3; ++j) m.nu(i, j) = i == j ? nan : -Snn(j, i) / Snn(i, i);
    m.G[i] = 1.0 / Sss(i, i);
  }
  if (!m.E.allFinite()) m.nu.setConstant(nan);
  return m;
}

}  // namespace trueaniso
