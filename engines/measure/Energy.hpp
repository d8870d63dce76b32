#pragma once
// Mechanical energy of the scene: what an undamped, frictionless-enough packing in a held cell
// conserves (docs/time-step.md measures the time step by its drift). Valid after a force
// evaluation (the contacts' forces and overlaps are those of the current positions).
//  - kinetic: 1/2 m |v|^2 with v the fluctuation velocity (the total one in a held cell), and
//    1/2 w.I w in the body frame;
//  - normal: the Hertz work int_0^delta N = (2/5) N delta (N ~ delta^3/2, HertzMindlin.hpp);
//  - tangential: |F_s|^2 / (2 k_s) at the current k_s, and |M_r|^2 / (2 k_r) for the rolling spring.
//    The law is incremental and k_s follows N, so these two are a spring energy, not a potential:
//    they are exact while N is constant, and a loading-unloading cycle under shear leaves an
//    O(dk_s/k_s) residue (Mindlin's own path dependence), not a time-step error.
#include "contact/HertzMindlin.hpp"
#include "core/Scene.hpp"

namespace trueaniso {

struct MechanicalEnergy {
  Real translational = 0, rotational = 0, normal = 0, tangential = 0, rolling = 0;
  Real kinetic() const { return translational + rotational; }
  Real elastic() const { return normal + tangential + rolling; }
  Real total() const { return kinetic() + elastic(); }
};

inline MechanicalEnergy mechanicalEnergy(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  MechanicalEnergy e;
  for (int b = 0; b < B.size(); ++b) {
    e.translational += 0.5 * B.mass[b] * B.vel[b].squaredNorm();
    if (s.blockRotations) continue;
    const Vec3 w = B.orientation[b].conjugate() * B.angVel[b];
    e.rotational += 0.5 * w.dot(B.inertia[b].cwiseProduct(w));
  }
  for (int c = 0; c < C.size(); ++c) {
    if (!C.active(c)) continue;
    const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
    const Real ks = law.shearStiffness(kn);
    e.normal += 0.4 * C.normalForce[c] * C.overlap[c];
    e.tangential += 0.5 * C.shearForce[c].squaredNorm() / ks;
    const Real kr = law.rollingStiffness(ks, C.rbar[c]);
    if (kr > 0) e.rolling += 0.5 * C.rollingMoment[c].squaredNorm() / kr;
  }
  return e;
}

}  // namespace trueaniso
