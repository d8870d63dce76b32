#include "dynamics/ContactForces.hpp"

#include <cmath>

namespace trueaniso {

template <bool Clumps, bool Rotations>
void ContactForces::computePairs(Scene& s, const HertzMindlin& law) {
  Contacts& C = s.contacts;
  const Bodies& B = s.bodies;
  const Members& M = s.members;
  const Vec3 h = s.cell.size;
  const Vec3 rate = s.cell.strainRate;
  const Real dt = s.dt;
  const Real ratio = law.shearToNormal();
  const int nc = C.size();
  long sliding = 0;

#pragma omp parallel for schedule(static) reduction(+ : sliding)
  for (int c = 0; c < nc; ++c) {
    const int i = C.m1[c], j = C.m2[c], a = C.b1[c], b = C.b2[c];
    const Vec3 sh = C.shift[c].cast<Real>().cwiseProduct(h);
    const Vec3& pi = Clumps ? M.pos[i] : B.pos[a];
    const Vec3 pj = (Clumps ? M.pos[j] : B.pos[b]) + sh;
    const Vec3 d = pj - pi;
    const Real ri = M.radius[i], rj = M.radius[j], rsum = ri + rj;
    const Real dist2 = d.squaredNorm();
    if (dist2 >= rsum * rsum) {  // not touching: a contact ends and forgets its history
      C.normalForce[c] = 0; C.kn[c] = 0; C.overlap[c] = rsum - std::sqrt(dist2);
      C.shearForce[c].setZero(); C.force[c].setZero();
      if (Rotations) { C.torque1[c].setZero(); C.torque2[c].setZero(); }
      continue;
    }
    const Real dist = std::sqrt(dist2);
    const Vec3 n = d / dist;
    const Real delta = rsum - dist;
    const Real N = law.normalForce(delta, C.rbar[c]);
    const Real kn = HertzMindlin::tangentFromForce(N, delta);
    const Vec3 branch = Clumps ? Vec3(B.pos[b] + sh - B.pos[a]) : d;

    // Lever arms from the body centres to the contact point, mid-overlap as in YADE's ScGeom.
    const Vec3 arm1 = (Clumps ? Vec3(pi - B.pos[a]) : Vec3::Zero()) + (ri - 0.5 * delta) * n;
    const Vec3 arm2 = (Clumps ? Vec3(pj - sh - B.pos[b]) : Vec3::Zero()) - (rj - 0.5 * delta) * n;

    // Relative velocity of the contact point: fluctuations, rigid rotations and the cell's
    // affine field acting on the branch between body centres.
    Vec3 vrel = B.vel[b] - B.vel[a] + rate.cwiseProduct(branch);
    Real twist = 0;
    if (Rotations) {
      vrel += B.angVel[b].cross(arm2) - B.angVel[a].cross(arm1);
      twist = 0.5 * dt * n.dot(B.angVel[a] + B.angVel[b]);
    }
    Vec3 Fs = C.shearForce[c];
    if (C.normalForce[c] > 0) Fs = HertzMindlin::rotateWithContact(Fs, C.normal[c], n, twist);
    else Fs.setZero();  // a contact that starts now has no tangential history
    const Vec3 dus = (vrel - n.dot(vrel) * n) * dt;
    if (law.updateShear(Fs, dus, ratio * kn, N)) ++sliding;

    const Vec3 F = N * n + Fs;  // force on body b; body a receives -F
    C.normal[c] = n; C.branch[c] = branch; C.overlap[c] = delta;
    C.normalForce[c] = N; C.kn[c] = kn; C.shearForce[c] = Fs; C.force[c] = F;
    if (Rotations) {
      C.torque1[c] = -arm1.cross(F);
      C.torque2[c] = arm2.cross(F);
    }
  }
  slidingContacts = sliding;
}

void ContactForces::gather(Scene& s) const {
  Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const int nb = B.size();
  const bool rot = !s.blockRotations;
#pragma omp parallel for schedule(static)
  for (int b = 0; b < nb; ++b) {
    Vec3 F = Vec3::Zero(), T = Vec3::Zero();
    for (int q = C.incBegin[b]; q < C.incBegin[b + 1]; ++q) {
      const int e = C.incidence[q];
      if (e >= 0) {
        F += C.force[e];
        if (rot) T += C.torque2[e];
      } else {
        F -= C.force[~e];
        if (rot) T += C.torque1[~e];
      }
    }
    B.force[b] = F;
    B.torque[b] = T;
  }
}

void ContactForces::apply(Scene& s) {
  require(!s.detectionInvalid, "contact forces need an up-to-date contact list: run ContactDetection first");
  const HertzMindlin law(s.material);
  const bool clumps = s.hasClumps(), rot = !s.blockRotations;
  if (clumps) {
    if (rot) computePairs<true, true>(s, law); else computePairs<true, false>(s, law);
  } else {
    if (rot) computePairs<false, true>(s, law); else computePairs<false, false>(s, law);
  }
  gather(s);
}

}  // namespace trueaniso
