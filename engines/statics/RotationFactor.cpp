#include "statics/RotationFactor.hpp"

#include <cmath>
#include <functional>
#include <limits>

#include "theory/Micromechanics.hpp"
#include "theory/Orthotropic.hpp"

namespace trueaniso {

namespace {

// Root of f in ZetaRange (theory/Micromechanics.hpp): intervals of 0.05 are scanned outwards from
// zeta = 1 (the root nearest the kinematic value is the meaningful one), the first sign change is
// bisected to round-off. NaN when no zeta in the range reproduces the modulus.
Real root(const std::function<Real(Real)>& f) {
  const Real lo = ZetaRange::lo, hi = ZetaRange::hi, step = 0.05;
  auto bisect = [&](Real x0, Real x1) {
    Real f0 = f(x0);
    for (int it = 0; it < 200 && x1 - x0 > 1e-15; ++it) {
      const Real xm = 0.5 * (x0 + x1), fm = f(xm);
      if ((fm < 0) == (f0 < 0)) { x0 = xm; f0 = fm; } else { x1 = xm; }
    }
    return 0.5 * (x0 + x1);
  };
  auto changes = [&](Real a, Real b) { return (f(a) < 0) != (f(b) < 0); };
  for (int k = 0; 1.0 + k * step < hi || 1.0 - k * step > lo; ++k) {
    const Real up = 1.0 + k * step, down = 1.0 - k * step;
    if (up + step <= hi && changes(up, up + step)) return bisect(up, up + step);
    if (down - step >= lo && changes(down - step, down)) return bisect(down - step, down);
  }
  return std::numeric_limits<Real>::quiet_NaN();
}

}  // namespace

Vec3 kinematicModuli(const Mat6& normalPart, const Mat6& shearPart, Real zeta) {
  return orthotropicModuli(normalPart + zeta * shearPart).E;
}

RotationFactor rotationFactor(const Mat6& An, const Mat6& As, const Vec3& free, const Vec3& blocked) {
  RotationFactor r;
  const Vec3 E1 = kinematicModuli(An, As, 1.0);
  auto Ei = [&](Real z, int i) { return kinematicModuli(An, As, z)[i]; };
  auto Eh = [&](Real z) { const Vec3 e = kinematicModuli(An, As, z); return 0.5 * (e[0] + e[1]); };
  for (int i = 0; i < 3; ++i) {
    r.zeta[i] = root([&](Real z) { return Ei(z, i) / free[i] - 1.0; });
    r.zetaRotation[i] = root([&](Real z) { return Ei(z, i) / E1[i] - free[i] / blocked[i]; });
  }
  const Real freeH = 0.5 * (free[0] + free[1]);
  const Real ratioH = freeH / (0.5 * (blocked[0] + blocked[1]));
  const Real E1h = 0.5 * (E1[0] + E1[1]);
  r.zetaH = root([&](Real z) { return Eh(z) / freeH - 1.0; });
  r.zetaRotationH = root([&](Real z) { return Eh(z) / E1h - ratioH; });
  r.zetaV = r.zeta[2];
  r.zetaRotationV = r.zetaRotation[2];
  return r;
}

}  // namespace trueaniso
