// The control logic of the servo and the probe without a scene: update(CellMeasurement, dt) driven
// by a synthetic linear specimen whose stiffness the test knows, so every answer has a closed form.
#include <gtest/gtest.h>

#include "control/CellServoLaw.hpp"
#include "control/StressProbe.hpp"
#include "control/TrueTriaxialServo.hpp"

using namespace trueaniso;

namespace {

// A linear elastic cell: stress = sigma0 + C (strain - strain0), compression positive, with a
// non-symmetric normal block (as a prestressed tangent) and the cell's log strain advanced by the
// controller's strain rates (extension positive: d strain = -rate dt). The controllers are told an
// affine stiffness `estimate` above the true diagonal, as the engines' affine estimate is.
struct LinearCell {
  Mat3 C;
  Vec3 sigma0 = Vec3::Constant(100e3);
  Vec3 strain = Vec3::Zero();
  Real estimateFactor = 1.5;
  Real unbalanced = 1e-6;
  Real dt = 1e-7;

  LinearCell() { C << 300e6, 80e6, 70e6, 90e6, 320e6, 60e6, 75e6, 65e6, 420e6; }
  CellMeasurement measure() const {
    CellMeasurement m;
    m.stress = sigma0 + C * strain;
    m.strain = strain;
    m.stiffness = estimateFactor * C.diagonal();
    m.unbalanced = unbalanced;
    return m;
  }
  void advance(const Vec3& rate) { strain -= rate * dt; }
};

}  // namespace

// One step of the law closes `gain` of the error through the stiffness estimate, with the sign of
// a compression-positive stress and an extension-positive rate; the cap holds in both directions.
TEST(CellServoLaw, ClosesAFractionOfTheErrorAndCapsTheRate) {
  CellServoLaw law{0.1, 5.0};
  const Vec3 K(1e8, 2e8, 4e8), stress(100e3, 100e3, 100e3), target(101e3, 99e3, 100e3);
  const Real dt = 1e-6;
  const Vec3 r = law.rates(target, stress, K, dt);
  EXPECT_NEAR(r.x(), -0.1 * 1e3 / (1e8 * dt), 1e-12);  // more compression wanted: the cell shrinks
  EXPECT_NEAR(r.y(), +0.1 * 1e3 / (2e8 * dt), 1e-12);
  EXPECT_EQ(r.z(), 0.0);
  const Vec3 capped = law.rates(Vec3::Constant(1e9), stress, K, dt);
  EXPECT_EQ(capped, Vec3::Constant(-5.0));
  const Vec3 unknownK = law.rates(target, stress, Vec3::Zero(), dt);  // no contact yet: full rate
  EXPECT_EQ(unknownK, Vec3(-5.0, 5.0, 5.0));
  EXPECT_THROW((CellServoLaw{0.0, 1.0}.validate()), InputError);
  EXPECT_THROW((CellServoLaw{0.5, -1.0}.validate()), InputError);
}

// State 21 of Table C1 (b = 0.5, sigma_z = 140 kPa) from the isotropic state: reached, every stress
// within the tolerance, the goal moving along the straight path of constant b and p, no overshoot
// beyond the tolerance (the 0.5 kPa), and the number of steps the path rate implies.
TEST(TrueTriaxialServo, ReachesState21AlongTheConstantBAndPPath) {
  LinearCell cell;
  TrueTriaxialServo servo;
  servo.goal = TrueTriaxialState{0.5, 140e3, 100e3};
  servo.law = CellServoLaw{0.05, 1e3};
  const Vec3 goal = servo.goal.stresses();  // (100, 60, 140) kPa
  ASSERT_NEAR(goal.x(), 100e3, 1e-9);
  ASSERT_NEAR(goal.y(), 60e3, 1e-9);
  Real worstB = 0, worstP = 0;
  long n = 0;
  while (servo.status != TrueTriaxialServo::Status::Reached && servo.status != TrueTriaxialServo::Status::Failed &&
         n < 1000000) {
    cell.advance(servo.update(cell.measure(), cell.dt));
    ++n;
    const Vec3& t = servo.target;
    if (std::abs(t.z() - t.y()) > 1e3) worstB = std::max(worstB, std::abs((t.x() - t.y()) / (t.z() - t.y()) - 0.5));
    worstP = std::max(worstP, std::abs(t.sum() / 3 - 100e3));
  }
  ASSERT_EQ(servo.status, TrueTriaxialServo::Status::Reached) << servo.message;
  const Vec3 s = cell.measure().stress;
  EXPECT_LT((s - goal).cwiseAbs().maxCoeff(), servo.stressTolerance);
  EXPECT_LT(worstB, 1e-9);  // the goal stays on the b = 0.5 line ...
  EXPECT_LT(worstP, 1e-6);  // ... at p = 100 kPa (round-off of the path interpolation only)
  EXPECT_LT(servo.overshoot.maxCoeff(), servo.stressTolerance);
  // 40 kPa at 2 Pa per step: the goal needs 20,000 steps; holding adds the settle steps and the lag.
  EXPECT_GE(servo.steps, 20000);
  EXPECT_LT(servo.steps, 40000);
}

// A specimen that cannot carry the state (its stress saturates below the goal) fails with a message
// naming the stall, long before the step cap.
TEST(TrueTriaxialServo, FailsCleanlyWhenTheSpecimenCannotFollow) {
  LinearCell cell;
  TrueTriaxialServo servo;
  servo.goal = TrueTriaxialState{0.5, 140e3, 100e3};
  servo.law = CellServoLaw{0.05, 1e3};
  servo.stallSteps = 5000;
  long n = 0;
  while (servo.status != TrueTriaxialServo::Status::Failed && servo.status != TrueTriaxialServo::Status::Reached &&
         n < 1000000) {
    CellMeasurement m = cell.measure();
    m.stress.z() = std::min(m.stress.z(), 120e3);  // the specimen yields at 120 kPa
    cell.advance(servo.update(m, cell.dt));
    ++n;
  }
  ASSERT_EQ(servo.status, TrueTriaxialServo::Status::Failed);
  EXPECT_NE(servo.message.find("stopped following the path"), std::string::npos) << servo.message;
  EXPECT_LT(n, 30000);
  EXPECT_TRUE(servo.done);
}

// The servo owns the loading friction: start() sets it on the scene (which may carry the probe's
// 1e23) before the first force evaluation; running it unstarted, or with a friction that is not a
// finite positive number, is refused.
TEST(TrueTriaxialServo, StartSetsTheLoadingFriction) {
  Scene s;
  s.material.friction = kProbeFriction;
  TrueTriaxialServo servo;
  EXPECT_THROW(servo.apply(s), InputError);
  servo.start(s);
  EXPECT_EQ(s.material.friction, kLoadingFriction);
  servo.loadingFriction = std::nan("");
  EXPECT_THROW(servo.start(s), InputError);
  servo.loadingFriction = 0.0;
  EXPECT_THROW(servo.start(s), InputError);
}

// The probe on each axis of the synthetic cell: with the two other stresses held, E_i = 1/S_ii and
// nu_ij = -S_ji/S_ii of the known compliance S = C^-1 (Eqs. 10-11). The stresses are held to a
// relative tolerance of 1e-6 of the increment, which bounds the error of E_i and nu_ij at ~1e-5.
TEST(StressProbe, MeasuresTheComplianceOfALinearCell) {
  LinearCell cell0;
  const Mat3 S = cell0.C.inverse();
  for (int axis = 0; axis < 3; ++axis) {
    LinearCell cell;
    StressProbe probe;
    probe.axis = axis;
    probe.relativeTolerance = 1e-6;
    probe.law = CellServoLaw{0.05, 1e3};
    probe.begin(cell.sigma0);
    long n = 0;
    while (probe.stage != StressProbe::Stage::Done && probe.stage != StressProbe::Stage::Failed && n < 200000) {
      cell.advance(probe.update(cell.measure(), cell.dt));
      ++n;
    }
    ASSERT_EQ(probe.stage, StressProbe::Stage::Done) << probe.message;
    EXPECT_GE(probe.gamma, probe.gammaTarget);
    EXPECT_NEAR(probe.youngModulus() * S(axis, axis), 1.0, 1e-5) << "axis " << axis;
    for (int j = 0; j < 3; ++j)
      if (j != axis) EXPECT_NEAR(probe.poissonRatio(j), -S(j, axis) / S(axis, axis), 1e-5) << axis << j;
  }
}

// A probe that never settles (the unbalanced force stays high) stops at maxSteps with a message;
// bad parameters are refused before anything runs.
TEST(StressProbe, FailsCleanlyAndRefusesBadParameters) {
  LinearCell cell;
  cell.unbalanced = 1.0;
  StressProbe probe;
  probe.maxSteps = 3000;
  probe.begin(cell.sigma0);
  long n = 0;
  while (probe.stage != StressProbe::Stage::Failed && probe.stage != StressProbe::Stage::Done && n < 10000) {
    cell.advance(probe.update(cell.measure(), cell.dt));
    ++n;
  }
  EXPECT_EQ(probe.stage, StressProbe::Stage::Failed);
  EXPECT_NE(probe.message.find("did not reach equilibrium"), std::string::npos);
  EXPECT_LE(n, 3001);
  for (auto bad : {3, -1}) {
    StressProbe p;
    p.axis = bad;
    EXPECT_THROW(p.begin(cell.sigma0), InputError);
  }
  StressProbe p;
  p.sign = 0;
  EXPECT_THROW(p.begin(cell.sigma0), InputError);
  p.sign = 1;
  p.gammaTarget = std::numeric_limits<Real>::infinity();
  EXPECT_THROW(p.begin(cell.sigma0), InputError);
  p.gammaTarget = 1e-6;
  EXPECT_THROW(p.begin(Vec3(100e3, -1.0, 100e3)), InputError);
}
