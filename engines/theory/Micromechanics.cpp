#include "theory/Micromechanics.hpp"

#include <cmath>
#include <sstream>

namespace trueaniso {

Mat9 stiffnessTensor(const Mat3& B, const Mat9& M, Real contactDensity, Real Cn, Real Cs, Real zeta) {
  const Real CsStar = zeta * Cs;
  Mat9 C = (contactDensity * (Cn - CsStar)) * M;
  // The tangential part C_s* B_ik delta_jl: only j = l pairs, i.e. rows 3i+j, columns 3k+j.
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) C(pairIndex(i, j), pairIndex(k, j)) += contactDensity * CsStar * B(i, k);
  return C;
}

Mat6 orthotropicStiffness(const Mat9& C) {
  auto c = [&](int i, int j, int k, int l) { return C(pairIndex(i, j), pairIndex(k, l)); };
  auto sym = [&](int i, int j, int k, int l) { return 0.5 * (c(i, j, k, l) + c(k, l, i, j)); };
  Mat6 V = Mat6::Zero();
  for (int i = 0; i < 3; ++i) V(i, i) = c(i, i, i, i);                 // A1-A3
  V(0, 1) = V(1, 0) = sym(0, 0, 1, 1);                                 // A4
  V(0, 2) = V(2, 0) = sym(0, 0, 2, 2);                                 // A5
  V(1, 2) = V(2, 1) = sym(1, 1, 2, 2);                                 // A6
  V(3, 3) = 0.5 * (c(1, 2, 1, 2) + c(2, 1, 2, 1));                     // A7
  V(4, 4) = 0.5 * (c(0, 2, 0, 2) + c(2, 0, 2, 0));                     // A8
  V(5, 5) = 0.5 * (c(0, 1, 0, 1) + c(1, 0, 1, 0));                     // A9
  return V;
}

void requireZeta(Real zeta) {
  if (!(zeta >= ZetaRange::lo && zeta <= ZetaRange::hi)) {
    std::ostringstream msg;
    msg << "zeta must lie in [" << ZetaRange::lo << ", " << ZetaRange::hi << "] (k_s* = zeta k_s, section 4.2), not "
        << zeta;
    throw InputError(msg.str());
  }
}

MicromechanicalPrediction predict(const Mat3& B, const Mat9& M, Real contactDensity, Real Cn, Real Cs, Real zeta) {
  requireZeta(zeta);
  MicromechanicalPrediction p;
  p.zeta = zeta;
  p.contactDensity = contactDensity;
  p.C = stiffnessTensor(B, M, contactDensity, Cn, Cs, zeta);
  p.voigt = orthotropicStiffness(p.C);
  p.moduli = orthotropicModuli(p.voigt);
  return p;
}

MicromechanicalPrediction predict(const Fabric& f, const Material& m, Real zeta, ContactDensity density) {
  const Real nv = density == ContactDensity::Eq36 ? f.contactDensityEq36() : f.contactDensityCount();
  return predict(f.B, f.M, nv, m.Cn(), m.Cs(), zeta);
}

}  // namespace trueaniso
