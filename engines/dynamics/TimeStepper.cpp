#include "dynamics/TimeStepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "contact/HertzMindlin.hpp"
#include "core/Parallel.hpp"

namespace trueaniso {

namespace {

// Largest eigenvalue of a symmetric 3x3 in closed form: with q = tr(a)/3 and a = q + p B, B having
// zero trace and unit Frobenius norm / sqrt 6, the eigenvalues are q + 2p cos(phi + 2 pi k/3) with
// cos(3 phi) = det(B)/2 (the trigonometric solution of the characteristic cubic); the largest is
// k = 0. It loses ~1e-8 of the value where two eigenvalues coincide (acos near +-1), immaterial to a
// time step; an iterative solver made the bound cost half a step.
Real largestEigenvalue(const Mat3& a) {
  const Real off = a(0, 1) * a(0, 1) + a(0, 2) * a(0, 2) + a(1, 2) * a(1, 2);
  const Real q = a.trace() / 3.0;
  const Real d0 = a(0, 0) - q, d1 = a(1, 1) - q, d2 = a(2, 2) - q;
  const Real p2 = d0 * d0 + d1 * d1 + d2 * d2 + 2.0 * off;
  if (!(p2 > 0)) return q;  // a multiple of the identity
  const Real p = std::sqrt(p2 / 6.0);
  Mat3 b = a;
  b.diagonal().array() -= q;
  const Real r = std::clamp(b.determinant() / (2.0 * p * p * p), -1.0, 1.0);
  return q + 2.0 * p * std::cos(std::acos(r) / 3.0);
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

// Calls f(e, c, kn) for each contact of body b that carries load (k_n > 0), in incidence order: c
// the contact, e its incidence entry (>= 0: b is the contact's second body), kn its k_n (Eq. 5).
template <class F>
void forEachLoadedContact(const Contacts& C, int b, F&& f) {
  for (int q = C.incBegin[b]; q < C.incBegin[b + 1]; ++q) {
    const int e = C.incidence[q];
    const int c = e >= 0 ? e : ~e;
    const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
    if (kn > 0) f(e, c, kn);
  }
}

}  // namespace

// The bounds' loops over bodies run on the team whenever the step's contact loop does, though a
// scene of 4000 spheres has fewer bodies than worthThreads asks for: every tenth step they are
// 8.5 % of a bare step's instructions there (per-axis rule). A minimum is exact in any order, so
// the bits are the serial loop's.
Real TimeStepper::stiffnessBound(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  const bool rot = !s.blockRotations;
  Real best = std::numeric_limits<Real>::infinity();
  const int nb = B.size();
#pragma omp parallel for schedule(static) reduction(min : best) if (worthThreadsBeside(nb, C.size()))
  for (int b = 0; b < nb; ++b) {
    Real kt = 0, kr = 0;
    forEachLoadedContact(C, b, [&](int e, int c, Real kn) {
      kt += kn;
      if (rot) {
        // Lever arm of the contact point about this body's centre: member offset + radius.
        const int m = e >= 0 ? C.m2[c] : C.m1[c];
        const Real l = s.members.offset[m].norm() + s.members.radius[m];
        const Real ks = law.shearStiffness(kn);
        // The rolling spring adds k_r to this body's rotational stiffness (0 when off: same bits).
        kr += ks * l * l + law.rollingStiffness(ks, C.rbar[c]);
      }
    });
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
#pragma omp parallel for schedule(static) reduction(min : best) if (worthThreadsBeside(nb, C.size()))
  for (int b = 0; b < nb; ++b) {
    // K_t = sum k_s 1 + (k_n - k_s) n n^T; K_r = sum k_s (|l|^2 1 - l l^T) + (k_n - k_s) c c^T with
    // c = l x n ([l]^T [l] = |l|^2 1 - l l^T, [l]^T n = -c), plus k_r (1 - n n^T).
    Mat3 Kt = Mat3::Zero(), Kr = Mat3::Zero();
    const bool sphere = B.memberCount(b) == 1 && s.members.offset[B.memberBegin[b]].isZero();
    bool loaded = false;
    forEachLoadedContact(C, b, [&](int e, int c, Real kn) {
      loaded = true;
      const Real ks = law.shearStiffness(kn);
      const Vec3& n = C.normal[c];
      const Mat3 nn = n * n.transpose();
      Kt.diagonal().array() += ks;
      Kt += (kn - ks) * nn;
      if (!rot) return;
      // The rolling spring resists the rotation normal to n (k_r = 0 when off).
      const Real kr = law.rollingStiffness(ks, C.rbar[c]);
      if (sphere) {  // l = -/+ (r - delta/2) n: c = 0, |l|^2 1 - l l^T = l^2 (1 - n n^T)
        const int m = e >= 0 ? C.m2[c] : C.m1[c];
        const Real l = s.members.radius[m] - 0.5 * C.overlap[c];
        const Real k = ks * l * l + kr;
        Kr.diagonal().array() += k;
        Kr -= k * nn;
      } else {
        const Vec3 l = arm(s, c, e >= 0 ? 2 : 1), cr = l.cross(n);
        Kr.diagonal().array() += ks * l.squaredNorm() + kr;
        Kr += (kn - ks) * cr * cr.transpose() - ks * l * l.transpose() - kr * nn;
      }
    });
    if (!loaded) continue;
    // The eigenvalue only where it can lower the minimum: the trace bounds it from above, so a body
    // whose 1/sqrt(trace) is not below the best so far cannot be the minimum (the same result).
    const Real bar = 1.0 / (best * best);
    Real w2 = Kt.trace() / B.mass[b] > bar ? largestEigenvalue(Kt) / B.mass[b] : 0.0;
    if (rot) {
      if (sphere) {  // isotropic inertia: every axis is principal
        if (Kr.trace() / B.inertia[b].x() > bar) w2 = std::max(w2, largestEigenvalue(Kr) / B.inertia[b].x());
      } else {  // in the principal frame, scaled by 1/sqrt(I_a) on each side
        const Mat3 R = B.orientation[b].toRotationMatrix();
        const Vec3 scale = B.inertia[b].cwiseSqrt().cwiseInverse();
        const Mat3 A = scale.asDiagonal() * (R.transpose() * Kr * R) * scale.asDiagonal();
        if (A.trace() > bar) w2 = std::max(w2, largestEigenvalue(A));
      }
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
    const Real translation = 1.0 / B.mass[a] + 1.0 / B.mass[b];
    Real w2 = kn * translation;
    if (rot) {
      const Real rolling = law.rollingStiffness(ks, C.rbar[c]) * (1.0 / B.inertia[a].minCoeff() + 1.0 / B.inertia[b].minCoeff());
      const bool spheres = B.memberCount(a) == 1 && B.memberCount(b) == 1 &&
                           s.members.offset[C.m1[c]].isZero() && s.members.offset[C.m2[c]].isZero();
      if (spheres) {
        // Arms along n: W = translation 1 + turning (1 - n n^T) commutes with K_c, so the modes are
        // the normal one, k_n translation, and the tangential ones, k_s (translation + turning).
        const Real l1 = s.members.radius[C.m1[c]] - 0.5 * C.overlap[c];
        const Real l2 = s.members.radius[C.m2[c]] - 0.5 * C.overlap[c];
        const Real turning = l1 * l1 / B.inertia[a].x() + l2 * l2 / B.inertia[b].x();
        w2 = std::max(w2, ks * (translation + turning)) + rolling;
      } else {
        // Mobility of the contact point: its relative acceleration per unit force on body 2 (and
        // the opposite on body 1).
        Mat3 W = translation * Mat3::Identity();
        for (int side : {1, 2}) {
          const int body = side == 1 ? a : b;
          const Mat3 R = B.orientation[body].toRotationMatrix();
          const Mat3 invI = R * B.inertia[body].cwiseInverse().asDiagonal() * R.transpose();
          const Mat3 L = cross(arm(s, c, side));
          W += L.transpose() * invI * L;
        }
        const Vec3& n = C.normal[c];
        const Mat3 root = std::sqrt(ks) * Mat3::Identity() + (std::sqrt(kn) - std::sqrt(ks)) * n * n.transpose();
        w2 = largestEigenvalue(root * W * root) + rolling;
      }
    }
    best = std::min(best, 2.0 / std::sqrt(w2));
  }
  return best;
}

void TimeStepper::apply(Scene& s) {
  // At 2 the body alone, its neighbours held, is at its own limit 2/omega: no packing is stable there.
  require(safety > 0 && safety < 2, "time step safety factor must lie in (0, 2)");
  require(referenceSafety > 0 && referenceSafety < 2, "reference time step safety factor must lie in (0, 2)");
  const Real reference = stiffnessBound(s);
  const Real bound = perAxis ? perAxisBound(s) : reference;
  s.dt = std::min(maxDt, std::isfinite(bound) ? safety * bound : maxDt);
  require(s.dt > 0 && std::isfinite(s.dt), "time step is not positive: check maxDt");
  const Real referenceCap = referenceMaxDt > 0 ? referenceMaxDt : maxDt * referenceSafety / safety;
  s.referenceDt = std::min(referenceCap, std::isfinite(reference) ? referenceSafety * reference : referenceCap);
}

}  // namespace trueaniso
