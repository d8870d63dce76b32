// The contact law (Eqs. 5-7) against closed forms computed here from G and nu, and the
// MercuryDPM-style drivers: load/unload, cyclic tangential loading, rigid rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include "Drivers.hpp"
#include "SameBits.hpp"
#include "contact/HertzMindlin.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

constexpr Real G = 18e9, nu = 0.15;
// Eq. (5) and Eq. (6) written out from the paper, independent of Material's coefficients.
Real knPaper(Real rbar, Real N) {
  return 0.75 * std::pow(8.0 * G / (3.0 * (1.0 - nu)), 2.0 / 3.0) * std::pow(rbar, 1.0 / 3.0) * std::pow(N, 1.0 / 3.0);
}
Real ksPaper(Real rbar, Real N) {
  return 2.0 * std::pow(3.0 * G * G * (1.0 - nu), 1.0 / 3.0) / (2.0 - nu) * std::pow(rbar, 1.0 / 3.0) *
         std::pow(N, 1.0 / 3.0);
}
Real rbarPaper(Real ri, Real rj) { return 1.0 / (0.5 * (1.0 / ri + 1.0 / rj)); }  // Eq. (7)

}  // namespace

// Five decades of normal force for equal and unequal radii. Tolerance 1e-12: the law computes
// k_n = 1.5 N/delta, algebraically identical to Eq. (5); only round-off separates them.
TEST(HertzMindlin, StiffnessesMatchEquations5and6) {
  const HertzMindlin law(paperMaterial());
  const Real pairs[][2] = {{0.1e-3, 0.1e-3}, {0.077e-3, 0.118e-3}, {1e-3, 0.25e-3}};
  for (const auto& rr : pairs) {
    const Real rbar = rbarPaper(rr[0], rr[1]);
    for (Real N = 1e-5; N <= 1.0001; N *= 10) {
      // Invert Hertz for the overlap that carries N, then evaluate the law there.
      const Real delta = std::pow(N / law.normalForce(1.0, rbar), 2.0 / 3.0);
      const Real Nlaw = law.normalForce(delta, rbar);
      EXPECT_NEAR(Nlaw / N, 1.0, 1e-12);
      const Real kn = HertzMindlin::normalStiffness(Nlaw, delta);
      EXPECT_NEAR(kn / knPaper(rbar, N), 1.0, 1e-12) << "N=" << N;
      EXPECT_NEAR(law.shearToNormal() * kn / ksPaper(rbar, N), 1.0, 1e-12) << "N=" << N;
      EXPECT_NEAR(law.knFromForce(N, rbar) / knPaper(rbar, N), 1.0, 1e-13);
      EXPECT_NEAR(law.ksFromForce(N, rbar) / ksPaper(rbar, N), 1.0, 1e-13);
      // The whole evaluator: a new contact's first tangential increment du gives -k_s du with
      // k_s of Eq. (6), and N of Hertz (well below the cap: du is 1e-6 of the slip distance).
      const Vec3 n(0, 0, 1), du(1e-6 * 0.5 * N / ksPaper(rbar, N), 0, 0);
      const HertzMindlin::Response r = law.evaluate(delta, rbar, n, false, n, Vec3::Zero(), du, 0.0);
      EXPECT_NEAR(r.N / N, 1.0, 1e-12);
      EXPECT_NEAR(-r.Fs.x() / du.x() / ksPaper(rbar, N), 1.0, 1e-12) << "N=" << N;
      EXPECT_FALSE(r.sliding);
      // Second method: the tangent is the derivative of the force law (central difference,
      // relative step 1e-5, truncation error ~1e-10).
      const Real h = 1e-5 * delta;
      const Real fd = (law.normalForce(delta + h, rbar) - law.normalForce(delta - h, rbar)) / (2 * h);
      EXPECT_NEAR(fd / kn, 1.0, 1e-8);
    }
  }
}

// Normal loading and unloading through the whole engine path: the force depends on the overlap
// alone (elastic, path independent), equal on the way in and out, equal to the closed form.
TEST(HertzMindlin, NormalLoadUnloadIsPathIndependent) {
  const Real r1 = 0.1e-3, r2 = 0.08e-3;
  auto s = twoSpheres(r1, r2, 0.0);
  Driver drv(s);
  const HertzMindlin law(s->material);
  const int steps = 200;
  const Real deltaMax = 2e-6, v = deltaMax / (steps * s->dt);
  std::vector<Real> up;
  s->bodies.vel[1] = Vec3(-v, 0, 0);
  for (int k = 0; k < steps; ++k) {
    drv.move();
    drv.evaluate();
    up.push_back(s->contacts.normalForce[0]);
  }
  s->bodies.vel[1] = Vec3(v, 0, 0);
  for (int k = steps - 2; k >= 0; --k) {
    drv.move();
    drv.evaluate();
    const Real delta = r1 + r2 - (s->bodies.pos[1] - s->bodies.pos[0]).norm();
    // Round-off of positions (~1e-19 m on 1e-3 m) against overlaps of 1e-8..1e-6 m.
    EXPECT_NEAR(s->contacts.normalForce[0], up[k], 1e-9 * up.back());
    EXPECT_NEAR(s->contacts.normalForce[0], law.normalForce(delta, rbarPaper(r1, r2)), 1e-12 * up.back());
    EXPECT_NEAR(s->contacts.shearForce[0].norm(), 0.0, 1e-12 * up.back());
  }
}

// Cyclic tangential loading at constant overlap, driven by spinning sphere 2 about z (its
// contact point slides along y, the geometry does not change). Expected: elastic-perfectly
// plastic loop with slope k_s and plateaus at +-mu N, computed here step by step in 1D.
TEST(HertzMindlin, CyclicTangentialLoadingHitsCoulombCap) {
  const Real r = 0.1e-3, delta = 1e-6, mu = 0.5;
  auto s = twoSpheres(r, r, delta, mu);
  Driver drv(s);
  drv.evaluate();
  const Real N = s->contacts.normalForce[0];
  const Real ks = HertzMindlin(s->material).shearStiffness(
      HertzMindlin::normalStiffness(s->contacts.normalForce[0], s->contacts.overlap[0]));
  const Real uSlip = mu * N / ks;
  const Real du = uSlip / 50.0;                   // 50 steps to the cap
  const Real arm = r - 0.5 * delta;
  const Real omega = du / (arm * s->dt);          // contact point speed of sphere 2: -arm*omega (y)
  Real expected = 0.0;                            // 1D model of F_y on sphere 2
  int slipping = 0;
  const int legs[] = {150, -300, 300, -150};      // +3 uSlip, to -3, to +3, back to 0
  for (int leg : legs) {
    const int sign = leg > 0 ? 1 : -1;
    s->bodies.angVel[1] = Vec3(0, 0, -sign * omega);  // contact point moves +sign*du along y
    for (int k = 0; k < std::abs(leg); ++k) {
      drv.evaluate();
      expected = std::clamp(expected - ks * sign * du, -mu * N, mu * N);
      const Vec3 Fs = s->contacts.shearForce[0];
      // Only round-off separates the engine and the 1D model (constant N, k_s, frame).
      ASSERT_NEAR(Fs.y(), expected, 1e-9 * mu * N) << "leg " << leg << " step " << k;
      ASSERT_NEAR(Fs.x(), 0.0, 1e-12 * N);
      ASSERT_LE(Fs.norm(), mu * N * (1 + 1e-14));
      if (std::abs(std::abs(expected) - mu * N) < 1e-15 * N) ++slipping;
    }
  }
  EXPECT_GT(slipping, 200);  // the cap was reached on each leg
}

// The probe switch: tangential force built up with mu = 1e23 to twice the 0.5 cap, then mu set
// back to 0.5 on the loaded contact. The next evaluation, with no relative motion, must cap the
// force at 0.5 N in its own direction; and with mu = 1e23 again nothing is capped.
TEST(HertzMindlin, FrictionSwitchedAtRunTimeCapsLoadedContacts) {
  const Real r = 0.1e-3, delta = 1e-6;
  auto s = twoSpheres(r, r, delta, 1e23);
  Driver drv(s);
  drv.evaluate();
  const Real N = s->contacts.normalForce[0];
  const Real ks = HertzMindlin(s->material).shearStiffness(
      HertzMindlin::normalStiffness(s->contacts.normalForce[0], s->contacts.overlap[0]));
  const Real arm = r - 0.5 * delta;
  const Real du = 2.0 * 0.5 * N / ks / 100.0;  // 100 steps to twice the 0.5 cap
  s->bodies.angVel[1] = Vec3(0, 0, -du / (arm * s->dt));
  for (int k = 0; k < 100; ++k) drv.evaluate();
  const Vec3 loaded = s->contacts.shearForce[0];
  ASSERT_NEAR(loaded.norm(), 1.0 * N, 0.02 * N);  // uncapped: ~2x the 0.5 cap
  s->bodies.angVel[1] = Vec3::Zero();
  s->material.friction = 0.5;
  drv.evaluate();
  const Vec3 capped = s->contacts.shearForce[0];
  EXPECT_NEAR(capped.norm(), 0.5 * N, 1e-12 * N);
  EXPECT_NEAR(capped.normalized().dot(loaded.normalized()), 1.0, 1e-12);
  s->material.friction = 1e23;
  drv.evaluate();
  EXPECT_NEAR(s->contacts.shearForce[0].norm(), 0.5 * N, 1e-12 * N);  // history kept, not restored
}

// A loaded pair turned as a rigid body (about an axis with a component along the normal, so the
// twist is exercised too): normal and tangential force magnitudes must not change.
TEST(HertzMindlin, RigidRotationKeepsForceMagnitudes) {
  const Real r1 = 0.1e-3, r2 = 0.12e-3, delta = 1e-6;
  auto s = twoSpheres(r1, r2, delta, 1e23);
  Driver drv(s);
  // Preload in shear (spin sphere 2 about z for a while), then stop.
  s->bodies.angVel[1] = Vec3(0, 0, 2000.0);
  for (int k = 0; k < 100; ++k) drv.evaluate();
  s->bodies.angVel[1].setZero();
  drv.evaluate();
  const Real N0 = s->contacts.normalForce[0];
  const Real F0 = s->contacts.shearForce[0].norm();
  ASSERT_GT(F0, 0.1 * N0);

  RigidRotation rigid(*s, Vec3(0.7, 0.2, 1.0).normalized() * 2e4);  // rad/s, 2e-4 rad per step
  const Vec3 f0 = s->contacts.shearForce[0];
  for (int k = 1; k <= 2000; ++k) {
    const Eigen::AngleAxisd R = rigid.place(k);
    drv.evaluate();
    // Exact rotations: only round-off (1e-12) may change the magnitudes over 2000 steps.
    ASSERT_NEAR(s->contacts.normalForce[0] / N0, 1.0, 1e-9);
    ASSERT_NEAR(s->contacts.shearForce[0].norm() / F0, 1.0, 1e-12);
    if (k == 2000) {
      // The direction follows the rigid rotation (0.4 rad in all) to first order in the step.
      const Vec3 rotated = R * f0;
      EXPECT_LT((s->contacts.shearForce[0] - rotated).norm() / F0, 1e-3);
    }
  }
}

// Degenerate geometry: a normal that flips sign loses its history instead of producing NaN.
TEST(HertzMindlin, RotationHandlesReversedNormal) {
  const Vec3 a(1, 0, 0), Fs(0, 2, 0);
  const Vec3 out = HertzMindlin::rotateWithContact(Fs, a, -a, 0.0);
  EXPECT_TRUE(out.allFinite());
  EXPECT_EQ(out.norm(), 0.0);
  const Vec3 same = HertzMindlin::rotateWithContact(Fs, a, a, 0.0);
  EXPECT_EQ(same, Fs);
}

// The force loop evaluates contacts 32 at a time, two per SSE2 register, with a scalar tail for an
// odd count. Each contact must get the bits it gets alone, whatever its place in the batch:
// 1000 random contacts (new and loaded, twisted and not, some sliding, one with its frame
// unchanged, one reversed) evaluated in batches of 31 and one at a time. Bitwise equality is the
// claim, so the tolerance is 0 (on a build for x86-64-v3, the last digits: SameBits.hpp).
TEST(HertzMindlin, BatchLanesGiveEachContactItsOwnBits) {
  const HertzMindlin law(paperMaterial());
  std::srand(7);
  auto u = [] { return 2.0 * std::rand() / RAND_MAX - 1.0; };
  HertzMindlin::Batch q;
  int slid = 0;
  for (int round = 0; round < 32; ++round) {
    const int m = 31;
    std::vector<HertzMindlin::Response> alone;
    for (int k = 0; k < m; ++k) {
      const Vec3 n = Vec3(u(), u(), u()).normalized();
      Vec3 p = (n + 0.01 * Vec3(u(), u(), u())).normalized();
      if (k == 3) p = n;    // unchanged frame (with twist 0 below: the force carried as it is)
      if (k == 5) p = -n;   // reversed normal: the old frame is meaningless, the force restarts
      const Vec3 Fs = 1e-3 * (Vec3(u(), u(), u()) - n * n.dot(Vec3(u(), u(), u())));
      const Vec3 dus = 1e-9 * (k % 4 == 0 ? 50.0 : 1.0) * Vec3(u(), u(), u());
      const Real twist = k == 3 || k % 7 == 0 ? 0.0 : 1e-4 * u();
      const Real delta = 1e-7 * (1.5 + u()), rbar = 1e-4 * (1.2 + 0.5 * u());
      const bool loaded = k % 6 != 1;
      alone.push_back(law.evaluate(delta, rbar, n, loaded, p, Fs, dus, twist));
      q.nx[k] = n.x(); q.ny[k] = n.y(); q.nz[k] = n.z();
      q.px[k] = p.x(); q.py[k] = p.y(); q.pz[k] = p.z();
      q.fx[k] = Fs.x(); q.fy[k] = Fs.y(); q.fz[k] = Fs.z();
      q.ux[k] = dus.x(); q.uy[k] = dus.y(); q.uz[k] = dus.z();
      q.twist[k] = twist; q.delta[k] = delta; q.rbar[k] = rbar; q.loaded[k] = loaded ? 1.0 : 0.0;
    }
    law.evaluate(q, m);
    for (int k = 0; k < m; ++k) {
      const Real scale = test::kSameBits * alone[k].Fs.norm();  // 0 on the baseline build (SameBits.hpp)
      EXPECT_NEAR(q.N[k], alone[k].N, test::kSameBits * alone[k].N);
      EXPECT_NEAR(q.fx[k], alone[k].Fs.x(), scale);
      EXPECT_NEAR(q.fy[k], alone[k].Fs.y(), scale);
      EXPECT_NEAR(q.fz[k], alone[k].Fs.z(), scale);
      EXPECT_EQ(q.sliding[k] != 0, alone[k].sliding);
      slid += alone[k].sliding;
    }
  }
  EXPECT_GT(slid, 0);  // the cap's own pass was taken
}
