#include "dynamics/TimeStepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/HertzMindlin.hpp"
#include "core/Parallel.hpp"

namespace trueaniso {

Real TimeStepper::stiffnessBound(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  const bool rot = !s.blockRotations;
  Real best = std::numeric_limits<Real>::infinity();
  const int nb = B.size();
#pragma omp parallel for schedule(static) reduction(min : best) if (worthThreads(nb))
  for (int b = 0; b < nb; ++b) {
    Real kt = 0, kr = 0;
    for (int q = C.incBegin[b]; q < C.incBegin[b + 1]; ++q) {
      const int e = C.incidence[q];
      const int c = e >= 0 ? e : ~e;
      const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
      if (kn <= 0) continue;
      kt += kn;
      if (rot) {
        // Lever arm of the contact point about this body's centre: member offset + radius.
        const int m = e >= 0 ? C.m2[c] : C.m1[c];
        const Real l = s.members.offset[m].norm() + s.members.radius[m];
        const Real ks = law.shearStiffness(kn);
        // The rolling spring adds k_r to this body's rotational stiffness (0 when off: same bits).
        kr += ks * l * l + law.rollingStiffness(ks, C.rbar[c]);
      }
    }
    if (kt > 0) best = std::min(best, std::sqrt(B.mass[b] / kt));
    if (kr > 0) best = std::min(best, std::sqrt(B.inertia[b].minCoeff() / kr));
  }
  return best;
}

Real TimeStepper::criticalPairStep(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  Real best = std::numeric_limits<Real>::infinity();
  const int nc = C.size();
#pragma omp parallel for schedule(static) reduction(min : best) if (worthThreads(nc))
  for (int c = 0; c < nc; ++c) {
    const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
    if (kn <= 0) continue;
    const int a = C.b1[c], b = C.b2[c];
    Real inv = 1.0 / B.mass[a] + 1.0 / B.mass[b];
    Real w2 = kn * inv;
    if (!s.blockRotations) {
      const Real l1 = s.members.offset[C.m1[c]].norm() + s.members.radius[C.m1[c]];
      const Real l2 = s.members.offset[C.m2[c]].norm() + s.members.radius[C.m2[c]];
      inv += l1 * l1 / B.inertia[a].minCoeff() + l2 * l2 / B.inertia[b].minCoeff();
      const Real ks = law.shearStiffness(kn);
      // Shear spring and rolling spring in one rotational mode: their frequencies add (a bound).
      w2 = std::max(w2, ks * inv + law.rollingStiffness(ks, C.rbar[c]) *
                                     (1.0 / B.inertia[a].minCoeff() + 1.0 / B.inertia[b].minCoeff()));
    }
    best = std::min(best, 2.0 / std::sqrt(w2));
  }
  return best;
}

void TimeStepper::apply(Scene& s) {
  require(safety > 0 && safety < 1, "time step safety factor must lie in (0, 1)");
  const Real bound = stiffnessBound(s);
  s.dt = std::min(maxDt, std::isfinite(bound) ? safety * bound : maxDt);
  require(s.dt > 0 && std::isfinite(s.dt), "time step is not positive: check maxDt");
}

}  // namespace trueaniso
