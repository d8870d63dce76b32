#include "theory/Orthotropic.hpp"

#include <limits>

namespace trueaniso {

OrthotropicModuli orthotropicModuli(const Mat6& C) {
  OrthotropicModuli m;
  const Mat3 block = C.topLeftCorner<3, 3>();
  m.Delta = block.determinant();
  const Mat3 S = block.inverse();
  for (int i = 0; i < 3; ++i) {
    m.E[i] = 1.0 / S(i, i);
    for (int j = 0; j < 3; ++j) m.nu(i, j) = i == j ? std::numeric_limits<Real>::quiet_NaN() : -S(j, i) / S(i, i);
    m.G[i] = C(3 + i, 3 + i);
  }
  return m;
}

}  // namespace trueaniso
