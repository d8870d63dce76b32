// The optional rolling sub-model of the contact law (contact/HertzMindlin.hpp, docs/rolling.md)
// with the contact-law drivers: closed form k_r theta up to the cap eta_r rbar N, reversibility,
// torques and angular momentum, history through detections and rigid rotations, bit-identity of
// the rolling loop with zero rolling moments, refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "Drivers.hpp"
#include "clump/ClumpTemplate.hpp"
#include "contact/HertzMindlin.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"
#include "statics/StaticStiffness.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

constexpr Real G = 18e9, nu = 0.15;
// Eq. (6) and Eq. (7) written out from the paper, independent of the law's own coefficients.
Real ksPaper(Real rbar, Real N) {
  return 2.0 * std::pow(3.0 * G * G * (1.0 - nu), 1.0 / 3.0) / (2.0 - nu) * std::pow(rbar, 1.0 / 3.0) *
         std::pow(N, 1.0 / 3.0);
}
Real rbarPaper(Real ri, Real rj) { return 1.0 / (0.5 * (1.0 / ri + 1.0 / rj)); }

std::shared_ptr<Scene> rollingPair(Real beta, Real eta, Real r1 = 0.1e-3, Real r2 = 0.12e-3, Real delta = 1e-6) {
  auto s = twoSpheres(r1, r2, delta, 1e23);  // no sliding: only the rolling cap may act
  s->material.rollingStiffness = beta;
  s->material.rollingFriction = eta;
  return s;
}

}  // namespace

// Sphere 2 rolls about y (normal along x) at a constant spin, positions fixed: the moment on it is
// -k_r theta y with k_r = beta k_s rbar^2, k_s of Eq. (6) from the contact's N, until the cap
// eta_r rbar N, where it stays. Tolerance 1e-10: k_s = 1.5 N/delta ratio is Eq. (6) up to
// round-off (1e-13, test_hertz_mindlin), and 200 equal increments add ~200 ulps at most.
TEST(RollingResistance, MomentIsKrThetaUpToTheCap) {
  const Real r1 = 0.1e-3, r2 = 0.12e-3, beta = 0.3, eta = 0.1;
  auto s = rollingPair(beta, eta, r1, r2);
  Driver drv(s);
  drv.evaluate();
  const Real N = s->contacts.normalForce[0];
  const Real rbar = rbarPaper(r1, r2);
  const Real kr = beta * ksPaper(rbar, N) * rbar * rbar;
  const Real cap = eta * rbar * N;
  const Real w = 4000.0;  // rad/s: 4e-5 rad a step
  s->bodies.angVel[1] = Vec3(0, w, 0);
  const int capStep = static_cast<int>(std::ceil(cap / (kr * w * s->dt)));
  ASSERT_GT(capStep, 20);  // the elastic branch is seen over several steps
  ASSERT_LT(capStep, 150);
  bool capSeen = false;
  for (int k = 1; k <= 200; ++k) {
    drv.evaluate();
    const Vec3 M = s->contacts.rollingMoment[0];
    const Real theta = w * s->dt * k;
    const Real expected = std::min(kr * theta, cap);
    ASSERT_NEAR(M.y() / -expected, 1.0, 1e-10) << "step " << k;
    ASSERT_EQ(M.x(), 0.0);  // in the tangent plane, along the rolling axis only
    ASSERT_EQ(M.z(), 0.0);
    if (kr * theta > cap) capSeen = true;
  }
  EXPECT_TRUE(capSeen);
  // The contact's normal force is unchanged by the rolling (positions fixed).
  EXPECT_EQ(s->contacts.normalForce[0], N);
}

// Below the cap the rolling spring is elastic: rolled forward and back by the same angle, the
// moment returns to zero (no energy stored). Tolerance: 1e-12 of the largest moment reached
// (round-off of 100 increments and their opposites).
TEST(RollingResistance, ElasticBranchIsReversible) {
  auto s = rollingPair(0.3, 1e3);  // cap far away
  Driver drv(s);
  drv.evaluate();
  s->bodies.angVel[1] = Vec3(0, 30.0, -20.0);
  for (int k = 0; k < 100; ++k) drv.evaluate();
  const Real peak = s->contacts.rollingMoment[0].norm();
  ASSERT_GT(peak, 0);
  s->bodies.angVel[1] = -s->bodies.angVel[1];
  for (int k = 0; k < 100; ++k) drv.evaluate();
  EXPECT_LT(s->contacts.rollingMoment[0].norm(), 1e-12 * peak);
}

// The moment acts on both bodies, opposite, on top of the shear force's lever torques: body 2
// gets arm2 x F + M, body 1 the opposite moment, and the total angular momentum change about a
// fixed point, sum (T + x x F), vanishes (1e-12 of the rolling moment: round-off).
TEST(RollingResistance, TorquesOnBothBodiesConserveAngularMomentum) {
  const Real r1 = 0.1e-3, r2 = 0.12e-3;
  auto s = rollingPair(0.5, 0.2, r1, r2);
  Driver drv(s);
  drv.evaluate();
  s->bodies.angVel[1] = Vec3(0, 40.0, 10.0);
  s->bodies.angVel[0] = Vec3(0, -5.0, 3.0);
  for (int k = 0; k < 30; ++k) drv.evaluate();
  const Contacts& C = s->contacts;
  const Vec3 M = C.rollingMoment[0];
  ASSERT_GT(M.norm(), 0);
  const Vec3 n = C.normal[0], Fc = C.force(0);
  const Real delta = C.overlap[0];
  const Vec3 arm1 = (r1 - 0.5 * delta) * n, arm2 = -(r2 - 0.5 * delta) * n;
  const Bodies& B = s->bodies;
  const Real scale = M.norm() + arm2.cross(Fc).norm();
  EXPECT_LT((B.torque[1] - (arm2.cross(Fc) + M)).norm(), 1e-12 * scale);
  EXPECT_LT((B.torque[0] - (-arm1.cross(Fc) - M)).norm(), 1e-12 * scale);
  const Vec3 L = B.torque[0] + B.torque[1] + B.pos[0].cross(B.force[0]) + B.pos[1].cross(B.force[1]);
  // pos x F is ~|pos| |F| = 2e-3 * F: its round-off dominates, 1e-15 of that.
  EXPECT_LT(L.norm(), 1e-12 * scale + 1e-14 * B.pos[1].norm() * Fc.norm());
}

// A rigid rotation of the loaded pair (both spheres spinning with the pair, no relative
// rotation) carries the rolling moment with the contact frame: its magnitude is kept to round-off
// (1e-12 over 2000 steps, exact rotations as for the shear force), its direction follows the
// rotation (1e-3: first order in the step, as the shear force in test_hertz_mindlin).
TEST(RollingResistance, RigidRotationKeepsMomentMagnitude) {
  auto s = rollingPair(0.3, 1e3);
  Driver drv(s);
  drv.evaluate();
  spinBody1(drv, Vec3(0, 40.0, 25.0), 50);
  drv.evaluate();
  const Vec3 M0 = s->contacts.rollingMoment[0];
  ASSERT_GT(M0.norm(), 0);

  RigidRotation rigid(*s, Vec3(0.7, 0.2, 1.0).normalized() * 2e4);
  for (int k = 1; k <= 2000; ++k) {
    const Eigen::AngleAxisd R = rigid.place(k);
    drv.evaluate();
    const Vec3 M = s->contacts.rollingMoment[0];
    ASSERT_NEAR(M.norm() / M0.norm(), 1.0, 1e-12) << "step " << k;
    ASSERT_LT(std::abs(M.dot(s->contacts.normal[0])), 1e-12 * M0.norm());  // stays in the tangent plane
    if (k == 2000) EXPECT_LT((M - R * M0).norm() / M0.norm(), 1e-3);
  }
}

// Contact detection keeps the moment of a pair it lists again, and a contact that opens forgets
// it: pulled apart and pushed back, the pair starts from zero.
TEST(RollingResistance, HistoryKeptByDetectionForgottenWhenOpen) {
  auto s = rollingPair(0.3, 1e3);
  Driver drv(s);
  drv.evaluate();
  spinBody1(drv, Vec3(0, 40.0, 0), 20);
  const Vec3 M = s->contacts.rollingMoment[0];
  s->detectionInvalid = true;  // forces a rebuild before the next evaluation
  const long before = drv.detection().rebuilds;
  drv.evaluate();
  ASSERT_EQ(drv.detection().rebuilds, before + 1);
  EXPECT_EQ(s->contacts.rollingMoment[0], M);  // bit for bit: same positions, dt-free carry

  const Vec3 p1 = s->bodies.pos[1];
  s->bodies.pos[1] += Vec3(2e-6, 0, 0);  // 1e-6 overlap -> 1e-6 gap, within the skin
  drv.evaluate();
  ASSERT_EQ(s->contacts.normalForce[0], 0.0);
  EXPECT_EQ(s->contacts.rollingMoment[0], Vec3::Zero());
  s->bodies.pos[1] = p1;
  drv.evaluate();
  EXPECT_GT(s->contacts.normalForce[0], 0.0);
  EXPECT_EQ(s->contacts.rollingMoment[0], Vec3::Zero());
}

// The rolling loop with its cap at zero (eta_r = 0: every moment is scaled to 0) must give the
// paper's loop's forces, torques and motion bit for bit: the sub-model adds only its own moment.
// A dense random gas run 300 steps with the integrator, rotations free.
TEST(RollingResistance, ZeroMomentsLeaveThePaperLoopBitIdentical) {
  auto make = [](Real beta) {
    auto s = std::make_shared<Scene>();
    s->material = paperMaterial();
    s->material.rollingStiffness = beta;
    s->material.rollingFriction = 0.0;
    std::mt19937_64 gen(7);
    std::uniform_real_distribution<Real> U(0, 1);
    const int n = 120;
    const Real r = 1e-4, side = std::cbrt(n * 4.0 / 3.0 * M_PI * r * r * r / 0.62);
    s->cell.setBox(Vec3::Constant(side));
    for (int i = 0; i < n; ++i) s->addSphere(Vec3(U(gen), U(gen), U(gen)) * side, r * (0.8 + 0.4 * U(gen)));
    return s;
  };
  auto off = make(0.0), on = make(0.4);
  ASSERT_FALSE(off->material.rolling());
  ASSERT_TRUE(on->material.rolling());
  auto run = [](std::shared_ptr<Scene> s) {
    Simulation sim = steppingChain(s, 0.2);
    s->dt = 2e-9;
    sim.run(300);
  };
  run(off);
  run(on);
  ASSERT_GT(off->contacts.size(), 0);
  for (int b = 0; b < off->bodies.size(); ++b) {
    ASSERT_EQ(off->bodies.pos[b], on->bodies.pos[b]) << b;
    ASSERT_EQ(off->bodies.angVel[b], on->bodies.angVel[b]) << b;
    ASSERT_EQ(off->bodies.torque[b], on->bodies.torque[b]) << b;
  }
  for (int c = 0; c < off->contacts.size(); ++c) ASSERT_EQ(off->contacts.shearForce[c], on->contacts.shearForce[c]);
}

// The time step accounts for the rolling spring: the rotational bound shrinks as beta grows.
TEST(RollingResistance, TimeStepBoundCountsTheRollingSpring) {
  auto s = rollingPair(0.0, 0.1);
  Driver drv(s);
  drv.evaluate();
  const Real off = TimeStepper::stiffnessBound(*s), offPair = TimeStepper::criticalPairStep(*s);
  s->material.rollingStiffness = 1.0;
  EXPECT_LT(TimeStepper::stiffnessBound(*s), off);
  EXPECT_LT(TimeStepper::criticalPairStep(*s), offPair);
}

// Bad input, before any work, with a message naming the parameter.
TEST(RollingResistance, RefusesBadParametersClumpsAndTheStaticSolve) {
  Material m = paperMaterial();
  for (Real bad : {-0.1, std::numeric_limits<Real>::quiet_NaN(), std::numeric_limits<Real>::infinity()}) {
    Material a = m, b = m;
    a.rollingStiffness = bad;
    b.rollingFriction = bad;
    EXPECT_THROW(a.validate(), InputError);
    EXPECT_THROW(b.validate(), InputError);
  }
  // Clumps: refused by the force loop.
  Scene c;
  c.material = paperMaterial();
  c.material.rollingStiffness = 0.3;
  const Real r = 1e-4;
  c.cell.setBox(Vec3::Constant(20 * r));
  c.addClump(Vec3::Constant(5 * r), Quat::Identity(), makeClumpTemplate({Vec3::Zero(), Vec3(r, 0, 0)}, {r, r}));
  c.addSphere(Vec3::Constant(5 * r) + Vec3(0, 1.9 * r, 0), r);
  ContactDetection().rebuild(c);
  try {
    ContactForces().apply(c);
    FAIL() << "clumps with rolling resistance were accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rolling resistance"), std::string::npos) << e.what();
  }
  // The static solve has no rolling springs: refused, not answered for another law.
  auto s = rollingPair(0.3, 0.1);
  try {
    StaticStiffness().compute(*s);
    FAIL() << "the static solve accepted rolling resistance";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not model rolling resistance"), std::string::npos) << e.what();
  }
}
