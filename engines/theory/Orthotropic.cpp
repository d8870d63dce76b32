#include "theory/Orthotropic.hpp"

#include <Eigen/LU>
#include <limits>

namespace trueaniso {

OrthotropicModuli orthotropicModuli(const Mat6& C) {
  constexpr Real nan = std::numeric_limits<Real>::quiet_NaN();
  OrthotropicModuli m;
  m.Delta = C.topLeftCorner<3, 3>().determinant();
  const Eigen::FullPivLU<Mat6> lu(C);
  if (!lu.isInvertible()) {
    m.E.setConstant(nan);
    m.nu.setConstant(nan);
    m.G.setConstant(nan);
    return m;
  }
  const Mat6 S = lu.inverse();
  for (int i = 0; i < 3; ++i) {
    m.E[i] = 1.0 / S(i, i);
    for (int j = 0; j < 3; ++j) m.nu(i, j) = i == j ? nan : -S(j, i) / S(i, i);
    m.G[i] = 1.0 / S(3 + i, 3 + i);
  }
  return m;
}

}  // namespace trueaniso
