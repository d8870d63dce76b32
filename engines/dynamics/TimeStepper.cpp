#include "dynamics/TimeStepper.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/HertzMindlin.hpp"
#include "core/Parallel.hpp"

namespace trueaniso {

namespace {

// Largest eigenvalue of a symmetric 3x3, iteratively (Eigen's closed form, computeDirect, lost
// 1e-9 of it on a turned dimer whose scaled matrix has one small and two equal eigenvalues).
Real largestEigenvalue(const Mat3& a) {
  Eigen::SelfAdjointEigenSolver<Mat3> solver;
  solver.compute(a, Eigen::EigenvaluesOnly);
  return solver.eigenvalues()(2);
}

// Contact stiffness on the relative displacement of the contact point: k_n n n^T + k_s (1 - n n^T).
Mat3 contactStiffness(Real kn, Real ks, const Vec3& n) {
  return ks * Mat3::Identity() + (kn - ks) * n * n.transpose();
}

// [l]: the matrix with [l] x = l x x.
Mat3 cross(const Vec3& l) {
  Mat3 c;
  c << 0, -l.z(), l.y(), l.z(), 0, -l.x(), -l.y(), l.x(), 0;
  return c;
}

// Arm from the centre of the body on `side` (1 or 2) of pair c to the contact point, world frame:
// the member's offset, then towards the other sphere to mid-overlap (normal n points from 1 to 2),
// where the force loop applies the contact force (dynamics/ContactForces.cpp).
Vec3 arm(const Scene& s, int c, int side) {
  const Contacts& C = s.contacts;
  const int m = side == 1 ? C.m1[c] : C.m2[c];
  const int b = side == 1 ? C.b1[c] : C.b2[c];
  const Real r = s.members.radius[m] - 0.5 * C.overlap[c];
  return s.bodies.orientation[b] * s.members.offset[m] + (side == 1 ? r : -r) * C.normal[c];
}

}  // namespace

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

Real TimeStepper::perAxisBound(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  const bool rot = !s.blockRotations;
  Real best = std::numeric_limits<Real>::infinity();
  const int nb = B.size();
#pragma omp parallel for schedule(static) reduction(min : best) if (worthThreads(nb))
  for (int b = 0; b < nb; ++b) {
    Mat3 Kt = Mat3::Zero(), Kr = Mat3::Zero();
    bool loaded = false;
    for (int q = C.incBegin[b]; q < C.incBegin[b + 1]; ++q) {
      const int e = C.incidence[q];
      const int c = e >= 0 ? e : ~e;
      const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
      if (kn <= 0) continue;
      loaded = true;
      const Real ks = law.shearStiffness(kn);
      const Mat3 Kc = contactStiffness(kn, ks, C.normal[c]);
      Kt += Kc;
      if (rot) {
        const Mat3 L = cross(arm(s, c, e >= 0 ? 2 : 1));
        Kr += L.transpose() * Kc * L;
        // The rolling spring resists the rotation normal to n (0 when off: adds nothing).
        const Real kr = law.rollingStiffness(ks, C.rbar[c]);
        Kr += kr * (Mat3::Identity() - C.normal[c] * C.normal[c].transpose());
      }
    }
    if (!loaded) continue;
    Real w2 = largestEigenvalue(Kt) / B.mass[b];
    if (rot) {
      // In the principal frame, scaled by 1/sqrt(I_a) on each side.
      const Mat3 R = B.orientation[b].toRotationMatrix();
      const Vec3 scale = B.inertia[b].cwiseSqrt().cwiseInverse();
      const Mat3 A = scale.asDiagonal() * (R.transpose() * Kr * R) * scale.asDiagonal();
      w2 = std::max(w2, largestEigenvalue(A));
    }
    if (w2 > 0) best = std::min(best, 1.0 / std::sqrt(w2));
  }
  return best;
}

Real TimeStepper::criticalPairStep(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  const bool rot = !s.blockRotations;
  Real best = std::numeric_limits<Real>::infinity();
  const int nc = C.size();
#pragma omp parallel for schedule(static) reduction(min : best) if (worthThreads(nc))
  for (int c = 0; c < nc; ++c) {
    const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
    if (kn <= 0) continue;
    const int a = C.b1[c], b = C.b2[c];
    const Real ks = law.shearStiffness(kn);
    // Mobility of the contact point: its relative acceleration per unit force on body 2 (and the
    // opposite on body 1).
    Mat3 W = (1.0 / B.mass[a] + 1.0 / B.mass[b]) * Mat3::Identity();
    Real rolling = 0;
    if (rot) {
      for (int side : {1, 2}) {
        const int body = side == 1 ? a : b;
        const Mat3 R = B.orientation[body].toRotationMatrix();
        const Mat3 invI = R * B.inertia[body].cwiseInverse().asDiagonal() * R.transpose();
        const Mat3 L = cross(arm(s, c, side));
        W += L.transpose() * invI * L;
      }
      rolling = law.rollingStiffness(ks, C.rbar[c]) * (1.0 / B.inertia[a].minCoeff() + 1.0 / B.inertia[b].minCoeff());
    }
    const Vec3& n = C.normal[c];
    const Mat3 root = std::sqrt(ks) * Mat3::Identity() + (std::sqrt(kn) - std::sqrt(ks)) * n * n.transpose();
    const Real w2 = largestEigenvalue(root * W * root) + rolling;
    best = std::min(best, 2.0 / std::sqrt(w2));
  }
  return best;
}

void TimeStepper::apply(Scene& s) {
  // At 2 the body alone, its neighbours held, is at its own limit 2/omega: no packing is stable there.
  require(safety > 0 && safety < 2, "time step safety factor must lie in (0, 2)");
  const Real bound = perAxis ? perAxisBound(s) : stiffnessBound(s);
  s.dt = std::min(maxDt, std::isfinite(bound) ? safety * bound : maxDt);
  require(s.dt > 0 && std::isfinite(s.dt), "time step is not positive: check maxDt");
}

}  // namespace trueaniso
