// TrueTriaxialServo's recovery of a packing that has lost its stress (lostStressFraction): a normal
// stress below that fraction of its goal is loaded at the strain-rate cap, every other rate is the
// proportional law's, bit for bit.
#include <gtest/gtest.h>

#include "control/CellServoLaw.hpp"
#include "control/TrueTriaxialServo.hpp"

using namespace trueaniso;

namespace {

// A linear isotropic cell, stress = sigma0 + K strain on each axis (compression positive), whose
// controllers are told an affine stiffness `estimate` times K: a loose packing, whose few contacts'
// affine stiffness overstates its own by orders.
struct SoftCell {
  Real K = 3e6;  // Pa per unit strain: a packing that barely resists
  Real estimate = 300.0;
  Vec3 sigma0 = Vec3::Constant(100e3);
  Mat3 F = Mat3::Identity();
  Real dt = 1e-7;
  CellMeasurement measure() const {
    CellMeasurement m;
    const Vec6 e = strainBetween(Mat3::Identity(), F);
    m.stress.setZero();
    for (int k = 0; k < 3; ++k) m.stress[k] = sigma0[k] + K * e[k];
    m.deformation = F;
    m.stiffness = Vec6::Constant(estimate * K);
    m.unbalanced = 1e-6;
    return m;
  }
  void advance(const Vec6& r) { F = (Mat3::Identity() + dt * CellServoLaw::velocityGradient(r)) * F; }
};

TrueTriaxialServo isotropicServo(Real lostFraction) {
  TrueTriaxialServo s;
  s.goal.b = 0;
  s.goal.sigmaZ = s.goal.p = 100e3;
  s.law.maxStrainRate = 30.0;  // the rate of inertial number 1e-3 for 0.2 mm grains at 100 kPa
  s.lostStressFraction = lostFraction;
  return s;
}

}  // namespace

TEST(TrueTriaxialServoRecovery, ALostNormalStressIsLoadedAtTheCapAndNothingElseChanges) {
  SoftCell a, b;
  TrueTriaxialServo on = isotropicServo(0.5), off = isotropicServo(0.0);
  on.update(a.measure(), a.dt);  // the start: the stress it finds is the path's start
  off.update(b.measure(), b.dt);
  a.sigma0.x() = b.sigma0.x() = 20e3;  // the packing loses its x stress (friction dropped)
  a.sigma0.y() = b.sigma0.y() = 60e3;  // above half its goal: the proportional law
  const Vec6 ra = on.update(a.measure(), a.dt), rb = off.update(b.measure(), b.dt);
  EXPECT_EQ(ra[0], -30.0);            // compressed at the cap
  EXPECT_GT(rb[0], -30.0);            // the law alone: the affine estimate's small strain
  for (int k = 1; k < 6; ++k) EXPECT_EQ(ra[k], rb[k]) << k;  // bit for bit
}

TEST(TrueTriaxialServoRecovery, BringsBackALostStressAtTheCapsRate) {
  // The packing finds 100 kPa at the start, then loses 80 % of it; its own stiffness is 1/300 of
  // the affine estimate. Back to half its goal it must strain 30e3 / K = 1e-2: at the cap (30 /s,
  // 3e-6 a step) 3,334 steps; the law alone starts at 8.9 /s and slows as the error closes.
  auto stepsToHalf = [](Real lost) {
    SoftCell c;
    TrueTriaxialServo s = isotropicServo(lost);
    s.update(c.measure(), c.dt);
    c.sigma0 = Vec3::Constant(20e3);
    long steps = 0;
    while (c.measure().stress[0] < 50e3 && steps < 1000000) {
      c.advance(s.update(c.measure(), c.dt));
      ++steps;
    }
    return steps;
  };
  const long with = stepsToHalf(0.5), without = stepsToHalf(0.0);
  EXPECT_NEAR(with, 3334, 2);
  EXPECT_GT(without, 3 * with);
}
