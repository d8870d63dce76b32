// Time step bound and pair limit against hand-computed bodies (the rotational stiffness about each
// principal axis from the contacts' arms, dynamics/TimeStepper.hpp), and the mechanical energy
// (measure/Energy.hpp) against closed forms.
#include <gtest/gtest.h>

#include <cmath>

#include "Drivers.hpp"
#include "RandomGas.hpp"
#include "contact/HertzMindlin.hpp"
#include "dynamics/ContactDetection.hpp"
#include "dynamics/ContactForces.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"
#include "measure/Energy.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

constexpr Real G = 18e9, nu = 0.15, rho = 2500;  // paperMaterial()
// Hertz between equal spheres of radius r, from the textbook form: E* = E / (2 (1 - nu^2)) =
// G / (1 - nu), R* = r/2; k_n = dN/d delta = 2 E* sqrt(R* delta); Mindlin k_s/k_n = 2(1-nu)/(2-nu).
Real hertzKn(Real r, Real delta) { return 2.0 * G / (1.0 - nu) * std::sqrt(0.5 * r * delta); }
Real mindlinKs(Real kn) { return 2.0 * (1.0 - nu) / (2.0 - nu) * kn; }

// A dimer of two balls of radius r at +-d along its body x axis, turned by q, and a free sphere of
// radius r touching the dimer's +x end along the dimer's axis with overlap delta. The dimer's mass
// and principal inertia are set by hand (I_y = I_z = m_s r^2 / 2, I_x = ratioX I_y: small, so
// that its rotation is the stiffest mode of the pair), so the hand values need no union volume.
struct DimerAndSphere {
  std::shared_ptr<Scene> s = std::make_shared<Scene>();
  Real r = 1e-4, d = 0.8e-4, delta = 1e-6, M, ms;
  Vec3 I;
  DimerAndSphere(const Quat& q, Real ratioX) {
    s->material = paperMaterial();
    s->cell.setBox(Vec3::Constant(40 * r));
    ms = rho * 4.0 / 3.0 * M_PI * r * r * r;
    M = 2 * ms;
    I = Vec3(ratioX, 1.0, 1.0) * 0.5 * ms * r * r;
    const Vec3 c = Vec3::Constant(20 * r);
    s->addClump(c, q, {Vec3(-d, 0, 0), Vec3(d, 0, 0)}, {r, r}, M, I, 2 * 4.0 / 3.0 * M_PI * r * r * r);
    s->addSphere(c + q * Vec3(d + 2 * r - delta, 0, 0), r);
    s->dt = 1e-9;
    s->refreshMembers();
    ContactDetection().apply(*s);
    ContactForces().apply(*s);
  }
};

}  // namespace

// The dimer's contact lies on its x axis: arm l = d + r - delta/2 along x (to mid-overlap, where the
// force acts), no stiffness about x, k_s l^2 about y and z. With I_x a millionth of I_y the bound must not notice I_x (a rule on the smallest
// principal inertia would cut the step by 1000), and turning the whole pair changes nothing.
// The sphere: translation lambda_max(K_c) = k_n over m_s, rotation k_s (r - delta/2)^2 over (2/5) m_s r^2.
// Tolerance 1e-9: the closed-form eigenvalues and the Hertz overlap to round-off.
TEST(TimeStepper, PerAxisBoundOfADimer) {
  for (const Quat& q : {Quat::Identity(), Quat(Eigen::AngleAxis<Real>(0.7, Vec3(1, 2, 3).normalized()))}) {
    DimerAndSphere p(q, 1e-6);
    ASSERT_EQ(p.s->contacts.size(), 1);
    ASSERT_TRUE(p.s->contacts.active(0));
    const Real kn = hertzKn(p.r, p.delta), ks = mindlinKs(kn);
    const Real l = p.d + p.r - 0.5 * p.delta, ls = p.r - 0.5 * p.delta;
    const Real dimerRot = ks * l * l / p.I.y();
    const Real w2 = std::max({kn / p.M, dimerRot, kn / p.ms, ks * ls * ls / (0.4 * p.ms * p.r * p.r)});
    ASSERT_EQ(w2, dimerRot);  // the dimer's rotation is the stiffest mode here
    // 1e-7: the closed-form eigenvalue near a double root (y and z here) keeps ~sqrt(eps) of it.
    EXPECT_NEAR(TimeStepper::perAxisBound(*p.s) * std::sqrt(w2), 1.0, 1e-7);
    EXPECT_LT(TimeStepper::stiffnessBound(*p.s), 0.01 * TimeStepper::perAxisBound(*p.s));  // sqrt(I_x): 1e-3
  }
}

// A sphere with contacts along +-x and +-y (a square, no z): about z every arm is normal to the
// axis, about x and y only half of them. Stiffest axis: z, 4 k_s l^2 (l = r - delta/2) against
// I = (2/5) m r^2; the rule on the sum of k_s l^2 gives the same here, and 2/3 of it for contacts all
// round (below).
// Tolerance 1e-9 as above.
TEST(TimeStepper, SphereRotationAboutItsStiffestAxis) {
  const Real r = 1e-4, delta = 1e-6, a = 2 * r - delta;
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  s->cell.setBox(Vec3(2 * a, 2 * a, 20 * r));  // a square lattice of 4 spheres, 4 contacts each
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) s->addSphere(Vec3((i + 0.5) * a, (j + 0.5) * a, 10 * r), r);
  Driver(s).evaluate();
  const Real kn = hertzKn(r, delta), ks = mindlinKs(kn), m = rho * 4.0 / 3.0 * M_PI * r * r * r;
  const Real l = r - 0.5 * delta;
  const Real w2 = std::max(4 * kn / m, 4 * ks * l * l / (0.4 * m * r * r));
  EXPECT_NEAR(TimeStepper::perAxisBound(*s) * std::sqrt(w2), 1.0, 1e-9);
  // Simple cubic, 6 contacts: each axis is normal to 4 of them: 4 k_s l^2, against 6 k_n in translation.
  auto c = std::make_shared<Scene>();
  c->material = paperMaterial();
  c->cell.setBox(Vec3::Constant(2 * a));
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k) c->addSphere(Vec3(i + 0.5, j + 0.5, k + 0.5) * a, r);
  Driver(c).evaluate();
  const Real w2c = std::max(6 * kn / m, 4 * ks * l * l / (0.4 * m * r * r));
  EXPECT_NEAR(TimeStepper::perAxisBound(*c) * std::sqrt(w2c), 1.0, 1e-9);
}

// The per-axis bound builds the 3x3 blocks only for the bodies whose scalar bound reaches the mode
// of the body with the largest bound. Against every body's mode taken alone: on overlapping
// spheres and on asymmetric dimers (the arms off the normals), with rotations free, with rolling
// springs, and with rotations blocked, each body's mode is under its bound and the bound is the
// largest mode's, to the bit (a maximum is exact, and 1/sqrt is monotone in floating point).
TEST(TimeStepper, PerAxisBoundIsTheStiffestBodysMode) {
  auto spheres = randomGasIn(Mat3::Identity(), 600, 0.6, 7);
  auto dimers = randomDimers(400, 0.6, 5);
  for (const auto& s : {spheres, dimers}) {
    s->dt = 1e-9;
    Driver(s).evaluate();
    for (int variant = 0; variant < 3; ++variant) {
      s->material.rollingStiffness = variant == 1 ? 0.5 : 0.0;
      s->blockRotations = variant == 2;
      Real largest = 0;
      int loaded = 0;
      for (int b = 0; b < s->bodies.size(); ++b) {
        const Real w2 = TimeStepper::stiffestMode(*s, b);
        EXPECT_LE(w2, TimeStepper::stiffestModeBound(*s, b) * (1 + 1e-8)) << "body " << b;
        largest = std::max(largest, w2);
        loaded += w2 > 0;
      }
      ASSERT_GT(loaded, s->bodies.size() / 2);
      EXPECT_EQ(TimeStepper::perAxisBound(*s), 1.0 / std::sqrt(largest)) << "variant " << variant;
      EXPECT_EQ(TimeStepper::bounds(*s, true).stiffness, TimeStepper::stiffnessBound(*s));
    }
  }
}

// The pair alone: normal mode k_n (1/M + 1/m_s); tangential modes (y and z of the dimer) with
// mobility 1/M + 1/m_s + l^2 / I_y + l_s^2 / I_s (arms to mid-overlap, l = d + r - delta/2,
// l_s = r - delta/2). I_x does not enter (zero arm about x).
TEST(TimeStepper, PairLimitOfADimerOnItsArms) {
  for (const Quat& q : {Quat::Identity(), Quat(Eigen::AngleAxis<Real>(-1.1, Vec3(0.3, -1, 2).normalized()))}) {
    DimerAndSphere p(q, 1e-6);
    const Real kn = hertzKn(p.r, p.delta), ks = mindlinKs(kn);
    const Real is = 0.4 * p.ms * p.r * p.r;
    const Real l = p.d + p.r - 0.5 * p.delta, ls = p.r - 0.5 * p.delta;
    const Real w2 = std::max(kn * (1 / p.M + 1 / p.ms), ks * (1 / p.M + 1 / p.ms + l * l / p.I.y() + ls * ls / is));
    EXPECT_NEAR(TimeStepper::criticalPairStep(*p.s) * std::sqrt(w2) / 2, 1.0, 1e-9);
  }
  // Two equal spheres: 2/omega with omega^2 = k_s (2/m + 2 l^2 / I), I = (2/5) m r^2, l = r - delta/2.
  const Real r = 1e-4, delta = 1e-6, m = rho * 4.0 / 3.0 * M_PI * r * r * r;
  auto s = twoSpheres(r, r, delta);
  Driver(s).evaluate();
  const Real ks = mindlinKs(hertzKn(r, delta));
  const Real l = r - 0.5 * delta;
  EXPECT_NEAR(TimeStepper::criticalPairStep(*s) * std::sqrt(ks * (2 / m + 2 * l * l / (0.4 * m * r * r))) / 2, 1.0, 1e-9);
  s->blockRotations = true;  // no rotation: the normal mode 2 k_n / m
  EXPECT_NEAR(TimeStepper::criticalPairStep(*s) * std::sqrt(2 * hertzKn(r, delta) / m) / 2, 1.0, 1e-9);
}

// Two spheres at overlap delta: the Hertz work (8/15) E* sqrt(R*) delta^(5/2) (the integral of
// N = (4/3) E* sqrt(R*) delta^(3/2)), and the kinetic energy of given velocities and spins; a
// turned dimer's rotational energy 1/2 sum I_a w_a^2 in its body frame. Tolerance 1e-12: round-off.
TEST(MechanicalEnergy, ClosedFormsOfTwoSpheresAndADimer) {
  const Real r1 = 1e-4, r2 = 1.3e-4, delta = 2e-6;
  auto s = twoSpheres(r1, r2, delta);
  Driver(s).evaluate();  // at rest: no tangential increment
  s->bodies.vel[0] = Vec3(0.1, -0.2, 0.05);
  s->bodies.angVel[1] = Vec3(3, 0, -4);
  const MechanicalEnergy e = mechanicalEnergy(*s);
  const Real Rstar = r1 * r2 / (r1 + r2);
  EXPECT_NEAR(e.normal / (8.0 / 15.0 * G / (1 - nu) * std::sqrt(Rstar) * std::pow(delta, 2.5)), 1.0, 1e-12);
  const Real m1 = rho * 4.0 / 3.0 * M_PI * r1 * r1 * r1, m2 = rho * 4.0 / 3.0 * M_PI * r2 * r2 * r2;
  EXPECT_NEAR(e.translational / (0.5 * m1 * 0.0525), 1.0, 1e-12);
  EXPECT_NEAR(e.rotational / (0.5 * 0.4 * m2 * r2 * r2 * 25), 1.0, 1e-12);
  EXPECT_EQ(e.tangential, 0.0);  // no shear history yet
  EXPECT_EQ(e.total(), e.translational + e.rotational + e.normal);

  const Quat q(Eigen::AngleAxis<Real>(0.9, Vec3(1, -1, 0.5).normalized()));
  DimerAndSphere p(q, 0.3);
  const Vec3 wBody(2, -1, 0.5);
  p.s->bodies.angVel[0] = q * wBody;
  const Real expected = 0.5 * (p.I.x() * 4 + p.I.y() * 1 + p.I.z() * 0.25);
  EXPECT_NEAR(mechanicalEnergy(*p.s).rotational / expected, 1.0, 1e-12);
}

// A shear spring loaded at constant N stores |F_s|^2 / (2 k_s): the work k_s u^2 / 2 of the
// displacement u that built it. Sphere 2 slides along y by u without rotation, far below mu N.
TEST(MechanicalEnergy, ShearSpringStoresItsWork) {
  const Real r = 1e-4, delta = 1e-6;
  auto s = twoSpheres(r, r, delta);
  s->blockRotations = true;
  Driver drv(s);
  drv.evaluate();
  const Real u = 1e-9;
  s->bodies.vel[1] = Vec3(0, u / s->dt, 0);
  drv.move();
  drv.evaluate();
  const Real ks = mindlinKs(hertzKn(r, delta));
  // The normal moves by u / (2r - delta) radians, which changes delta by O(u^2 / r): 1e-9 relative.
  EXPECT_NEAR(mechanicalEnergy(*s).tangential / (0.5 * ks * u * u), 1.0, 1e-6);
}

// The reference step (Scene::referenceDt, the unit of the servos' per-step settings) is the
// smallest-inertia rule's step whatever rule sets dt: under that rule itself it is dt to the bit (a
// step scale of exactly 1, so its results do not change), under the per-axis rule it is the
// smallest-inertia bound at the reference factor, and the cap takes the reference factor too.
TEST(TimeStepper, ReferenceStepIsTheSmallestInertiaRules) {
  DimerAndSphere pair(Quat::Identity(), 1e-6);
  Scene& s = *pair.s;
  TimeStepper plain;
  plain.apply(s);
  EXPECT_EQ(s.referenceDt, s.dt);
  EXPECT_EQ(s.stepScale(), 1.0);
  EXPECT_EQ(s.dt, plain.safety * TimeStepper::stiffnessBound(s));
  TimeStepper fast;
  fast.perAxis = true;
  fast.safety = 0.8;
  fast.apply(s);
  EXPECT_EQ(s.dt, 0.8 * TimeStepper::perAxisBound(s));
  EXPECT_EQ(s.referenceDt, 0.5 * TimeStepper::stiffnessBound(s));
  EXPECT_GT(s.stepScale(), 1.0);  // the dimer's I_x, tiny, binds only the smallest-inertia rule
  // A binding cap: dt = maxDt, the reference at maxDt x 0.5 / 0.8 (or the cap it is given).
  fast.maxDt = 0.1 * s.dt;
  fast.apply(s);
  EXPECT_EQ(s.dt, fast.maxDt);
  EXPECT_DOUBLE_EQ(s.referenceDt, std::min(fast.maxDt * 0.5 / 0.8, 0.5 * TimeStepper::stiffnessBound(s)));
  fast.referenceMaxDt = 1e-30;
  fast.apply(s);
  EXPECT_EQ(s.referenceDt, 1e-30);
  fast.referenceSafety = 2.0;
  EXPECT_THROW(fast.apply(s), InputError);
  Scene bare;
  EXPECT_EQ(bare.stepScale(), 1.0);  // no reference known: the step is the unit
}
