#include "dynamics/TimeStepper.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

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

bool isSphere(const Scene& s, int b) {
  return s.bodies.memberCount(b) == 1 && s.members.offset[s.bodies.memberBegin[b]].isZero();
}

// The scalar sums of body b over its loaded contacts: sum k_n; the stiffness rule's rotational
// sum k_s l^2 + k_r, l = |member offset| + radius; and the rotational part of stiffestModeBound.
struct BodySums {
  Real kt = 0, kr = 0, krBound = 0;
};

BodySums bodySums(const Scene& s, const HertzMindlin& law, bool rot, int b) {
  const Contacts& C = s.contacts;
  const bool sphere = isSphere(s, b);
  BodySums sum;
  forEachLoadedContact(C, b, [&](int e, int c, Real kn) {
    sum.kt += kn;
    if (rot) {
      // Lever arm of the contact point about this body's centre: member offset + radius.
      const int m = e >= 0 ? C.m2[c] : C.m1[c];
      const Real l = s.members.offset[m].norm() + s.members.radius[m];
      const Real ks = law.shearStiffness(kn);
      // The rolling spring adds k_r to this body's rotational stiffness (0 when off: same bits).
      const Real kroll = law.rollingStiffness(ks, C.rbar[c]);
      sum.kr += ks * l * l + kroll;
      if (!sphere) sum.krBound += std::max(kn, ks) * l * l + kroll;
    }
  });
  if (sphere) sum.krBound = sum.kr;
  return sum;
}

// Relative margin of the pruning below: the closed-form eigenvalue may exceed the exact one by
// ~1e-8 of it (largestEigenvalue), so a body is left out only when its bound is clearly below.
constexpr Real kBoundMargin = 1e-6;

}  // namespace

Real TimeStepper::stiffestMode(const Scene& s, int b) {
  // K_t = sum k_s 1 + (k_n - k_s) n n^T; K_r = sum k_s (|l|^2 1 - l l^T) + (k_n - k_s) c c^T with
  // c = l x n ([l]^T [l] = |l|^2 1 - l l^T, [l]^T n = -c), plus k_r (1 - n n^T).
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  const bool rot = !s.blockRotations;
  Mat3 Kt = Mat3::Zero(), Kr = Mat3::Zero();
  const bool sphere = isSphere(s, b);
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
  if (!loaded) return 0;
  Real w2 = largestEigenvalue(Kt) / B.mass[b];
  if (rot) {
    if (sphere) {  // isotropic inertia: every axis is principal
      w2 = std::max(w2, largestEigenvalue(Kr) / B.inertia[b].x());
    } else {  // in the principal frame, scaled by 1/sqrt(I_a) on each side
      const Mat3 R = B.orientation[b].toRotationMatrix();
      const Vec3 scale = B.inertia[b].cwiseSqrt().cwiseInverse();
      const Mat3 A = scale.asDiagonal() * (R.transpose() * Kr * R) * scale.asDiagonal();
      w2 = std::max(w2, largestEigenvalue(A));
    }
  }
  return w2;
}

Real TimeStepper::stiffestModeBound(const Scene& s, int b) {
  const BodySums sum = bodySums(s, HertzMindlin(s.material), !s.blockRotations, b);
  return std::max(sum.kt / s.bodies.mass[b], sum.krBound / s.bodies.inertia[b].minCoeff());
}

// One walk over each body's contacts gives the stiffness rule and each body's bound of its
// stiffest mode; the 3x3 blocks and their eigenvalues are then built only for the bodies whose
// bound reaches the largest mode found so far, starting from that of the body with the largest
// bound (3 % of the bodies in a packing of 4000 spheres, 31 % of 4000 clump2 dimers, whose bound
// is looser), and the maximum is exact: a body left out cannot exceed it. The loops run on the team whenever the step's contact loop does
// (worthThreadsBeside); a minimum and a maximum are exact in any order, so the bits are the
// serial loops'.
TimeStepper::Bounds TimeStepper::bounds(const Scene& s, bool perAxis) {
  const Bodies& B = s.bodies;
  const HertzMindlin law(s.material);
  const bool rot = !s.blockRotations;
  const int nb = B.size();
  const bool team = worthThreadsBeside(nb, s.contacts.size());
  std::vector<Real> upper(perAxis ? nb : 0);
  Real best = std::numeric_limits<Real>::infinity();
#pragma omp parallel for schedule(static) reduction(min : best) if (team)
  for (int b = 0; b < nb; ++b) {
    const BodySums sum = bodySums(s, law, rot, b);
    if (sum.kt > 0) best = std::min(best, std::sqrt(B.mass[b] / sum.kt));
    if (sum.kr > 0) best = std::min(best, std::sqrt(B.inertia[b].minCoeff() / sum.kr));
    if (perAxis) upper[b] = std::max(sum.kt / B.mass[b], sum.krBound / B.inertia[b].minCoeff());
  }
  Bounds out{best, std::numeric_limits<Real>::infinity()};
  if (!perAxis || nb == 0) return out;
  const int top = static_cast<int>(std::max_element(upper.begin(), upper.end()) - upper.begin());
  if (!(upper[top] > 0)) return out;
  const Real floor = stiffestMode(s, top);
  Real w2 = floor;
#pragma omp parallel for schedule(static) reduction(max : w2) if (team)
  for (int b = 0; b < nb; ++b) {
    if (upper[b] * (1 + kBoundMargin) < std::max(floor, w2)) continue;
    w2 = std::max(w2, stiffestMode(s, b));
  }
  out.perAxis = 1.0 / std::sqrt(w2);
  return out;
}

Real TimeStepper::stiffnessBound(const Scene& s) { return bounds(s, false).stiffness; }

Real TimeStepper::perAxisBound(const Scene& s) { return bounds(s, true).perAxis; }

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
  const Bounds both = bounds(s, perAxis);
  const Real reference = both.stiffness;
  const Real bound = perAxis ? both.perAxis : reference;
  s.dt = std::min(maxDt, std::isfinite(bound) ? safety * bound : maxDt);
  require(s.dt > 0 && std::isfinite(s.dt), "time step is not positive: check maxDt");
  const Real referenceCap = referenceMaxDt > 0 ? referenceMaxDt : maxDt * referenceSafety / safety;
  s.referenceDt = std::min(referenceCap, std::isfinite(reference) ? referenceSafety * reference : referenceCap);
}

}  // namespace trueaniso
