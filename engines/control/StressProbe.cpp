#include "control/StressProbe.hpp"

#include <cmath>
#include <sstream>

#include "control/TrueTriaxialPath.hpp"

namespace trueaniso {

void StressProbe::begin(const Vec3& hold) {
  require(axis >= 0 && axis <= 2, "probe axis must be x, y or z (0, 1, 2)");
  require(sign == 1 || sign == -1, "probe sign must be +1 or -1");
  require(std::isfinite(gammaTarget) && gammaTarget > 0, "probe gamma must be a finite number > 0");
  require(increment >= 0, "probe increment must be >= 0 (0: stop at gamma)");
  require(relativeTolerance > 0 && relativeTolerance < 1, "probe tolerance must lie in (0, 1)");
  require(unbalancedTolerance > 0 && rampSteps > 0 && settleSteps >= 1 && maxSteps > 0,
          "probe tolerances and step counts must be > 0");
  require((hold.array() > 0).all(), "probe: the held stresses must be > 0 (compression positive)");
  law.validate();
  holdGoal_ = hold;
  target = holdGoal_;
  stage = Stage::Relax;
  message.clear();
  steps = relaxSteps = rampStepsDone = holdSteps = settled_ = 0;
  dStress.setZero();
  dStrain.setZero();
  gamma = 0;
  done = false;
}

void StressProbe::start(Scene& s, const Vec3& hold) {
  begin(hold);
  snapshot_ = std::make_shared<Scene>(s);
  s.material.friction = probeFriction;
  if (restrainRotations) {
    s.blockRotations = true;
    for (Vec3& w : s.bodies.angVel) w.setZero();
  }
}

void StressProbe::restore(Scene& s) const {
  require(snapshot_ != nullptr, "probe restore without a start");
  s = *snapshot_;
  s.detectionInvalid = true;
}

void StressProbe::apply(Scene& s) {
  if (stage == Stage::Idle) throw InputError("StressProbe: call start(scene, hold) before running it");
  if (stage == Stage::Done || stage == Stage::Failed) {
    done = true;
    return;
  }
  s.cell.strainRate = update(CellMeasurement::of(s), s.dt);
}

Vec3 StressProbe::update(const CellMeasurement& m, Real dt) {
  if (stage == Stage::Idle) throw InputError("StressProbe: begin() before update()");
  if (stage == Stage::Done || stage == Stage::Failed) {
    done = true;
    return Vec3::Zero();
  }
  ++steps;
  stress = m.stress;
  const Vec3& strain = m.strain;
  unbalanced = m.unbalanced;
  const Vec3& K = m.stiffness;

  if (stage == Stage::Relax) {
    ++relaxSteps;
    // Before any increment exists, "small" is judged against the expected increment from the
    // affine stiffness (an upper bound, so the criterion is on the safe side).
    const Real expected = increment > 0 ? increment : K[axis] * gammaTarget;
    const bool ok = (stress - holdGoal_).cwiseAbs().maxCoeff() < relativeTolerance * expected &&
                    unbalanced < unbalancedTolerance;
    settled_ = ok ? settled_ + 1 : 0;
    if (settled_ >= settleSteps) {
      refStress = stress;
      refStrain = strain;
      target = refStress;
      rampRate_ = (increment > 0 ? increment : 0.5 * K[axis] * gammaTarget) / rampSteps;
      stage = Stage::Ramp;
      settled_ = 0;
    }
  } else if (stage == Stage::Ramp) {
    ++rampStepsDone;
    gamma = shearStrainGamma(strain - refStrain);
    const Real reached = sign * (target[axis] - refStress[axis]);
    const bool stop = increment > 0 ? reached >= increment : gamma >= gammaTarget;
    if (stop) {
      if (increment > 0) target[axis] = refStress[axis] + sign * increment;
      stage = Stage::Hold;
    } else {
      target[axis] += sign * rampRate_;
    }
  } else if (stage == Stage::Hold) {
    ++holdSteps;
    const Real inc = std::abs(target[axis] - refStress[axis]);
    const bool ok = (stress - target).cwiseAbs().maxCoeff() < relativeTolerance * inc &&
                    unbalanced < unbalancedTolerance;
    settled_ = ok ? settled_ + 1 : 0;
    if (settled_ >= settleSteps) {
      dStress = stress - refStress;
      dStrain = strain - refStrain;
      gamma = shearStrainGamma(dStrain);
      stage = Stage::Done;
      done = true;
      return Vec3::Zero();
    }
  }
  if (steps > maxSteps) {
    std::ostringstream msg;
    msg << "probe on axis " << "xyz"[axis] << " did not reach equilibrium within " << maxSteps << " steps";
    message = msg.str();
    stage = Stage::Failed;
    done = true;
    return Vec3::Zero();
  }
  return law.rates(target, stress, K, dt);
}

}  // namespace trueaniso
