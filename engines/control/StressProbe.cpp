#include "control/StressProbe.hpp"

#include <cmath>
#include <sstream>

#include "control/TrueTriaxialPath.hpp"

namespace trueaniso {

namespace {
const char* const kAxisNames[6] = {"x", "y", "z", "yz", "xz", "xy"};

// Largest |a_I - b_I| over the components in the mask.
Real maskedError(const Vec6& a, const Vec6& b, unsigned mask) {
  Real e = 0;
  for (int I = 0; I < 6; ++I)
    if (mask >> I & 1u) e = std::max(e, std::abs(a[I] - b[I]));
  return e;
}
}  // namespace

void StressProbe::begin(const Vec6& hold) {
  require(axis >= 0 && axis <= 5, "probe axis must be x, y, z, yz, xz or xy (0-5)");
  require(axis < 3 || controlShear || holdOtherStrains,
          "a shear probe needs the shear stresses under control (controlShear): with the cell's shear strains "
          "held there is nothing to probe");
  require(sign == 1 || sign == -1, "probe sign must be +1 or -1");
  require(std::isfinite(gammaTarget) && gammaTarget > 0, "probe gamma must be a finite number > 0");
  require(increment >= 0 && std::isfinite(increment), "probe increment must be a finite number >= 0 (0: stop at gamma)");
  require(probeFriction > 0, "probe friction must be > 0 (the paper's 1e23 suppresses sliding)");
  require(relativeTolerance > 0 && relativeTolerance < 1, "probe tolerance must lie in (0, 1)");
  require(unbalancedTolerance > 0 && rampSteps > 0 && settleSteps >= 1 && maxSteps > 0,
          "probe tolerances and step counts must be > 0");
  require(std::isfinite(stepScale) && stepScale > 0, "probe: the step scale must be a finite number > 0");
  require(hold.allFinite() && (hold.head<3>().array() > 0).all(),
          "probe: the held normal stresses must be > 0 (compression positive) and every held stress finite");
  law.validate();
  holdGoal_ = hold;
  target = holdGoal_;
  stage = Stage::Relax;
  message.clear();
  steps = relaxSteps = rampStepsDone = holdSteps = settled_ = 0;
  dStress.setZero();
  dStrain.setZero();
  dStressFirst.setZero();
  dStrainFirst.setZero();
  dStressSecond.setZero();
  dStrainSecond.setZero();
  side = 0;
  restorePending_ = false;
  relaxed_.reset();
  gamma = 0;
  done = false;
}

void StressProbe::start(Scene& s, const Vec6& hold) {
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
  stepScale = s.stepScale();
  const Stage before = stage;
  const Vec6 rates = update(CellMeasurement::of(s), s.dt);
  if (twoSided && before == Stage::Relax && stage == Stage::Ramp) {
    relaxed_ = std::make_shared<Scene>(s);  // as this step found it, before its rates act
  } else if (restorePending_) {
    const Contacts& now = s.contacts;
    // The contact list as the detection engine last built it: the relaxed one unless a rebuild
    // came between (then the detection's reference positions are no longer the relaxed list's,
    // and it must build again).
    const bool sameList = now.m1 == relaxed_->contacts.m1 && now.m2 == relaxed_->contacts.m2 &&
                          now.shift == relaxed_->contacts.shift;
    s = *relaxed_;
    if (!sameList) s.detectionInvalid = true;
    restored();
  }
  s.cell.velGrad = CellServoLaw::velocityGradient(rates);
}

Real StressProbe::strainMeasure() const {
  return shearProbe() ? std::abs(dStrain[axis]) : shearStrainGamma(dStrain.head<3>());
}

// The Hold of a side has settled: keep its increments; after the first side of a two-sided
// probe, start the second from the relaxed state (the host puts it back), else finish.
void StressProbe::finishSide() {
  (side == 0 ? dStressFirst : dStressSecond) = dStress;
  (side == 0 ? dStrainFirst : dStrainSecond) = dStrain;
  if (twoSided && side == 0) {
    side = 1;
    target = refStress;
    settled_ = 0;
    stage = Stage::Ramp;
    restorePending_ = true;
    return;
  }
  if (twoSided) {
    dStress = 0.5 * (dStressFirst - dStressSecond);
    dStrain = 0.5 * (dStrainFirst - dStrainSecond);
    gamma = strainMeasure();
  }
  stage = Stage::Done;
  done = true;
}

Vec6 StressProbe::update(const CellMeasurement& m, Real dt) {
  if (stage == Stage::Idle) throw InputError("StressProbe: begin() before update()");
  require(!restorePending_, "StressProbe: a two-sided probe's host must put the relaxed state back (restorePending) "
                            "before the next update()");
  if (stage == Stage::Done || stage == Stage::Failed) {
    done = true;
    return Vec6::Zero();
  }
  ++steps;
  stress = m.stress;
  unbalanced = m.unbalanced;
  const Vec6& K = m.stiffness;
  const unsigned mask = stressMask();
  const int sideSign = side == 0 ? sign : -sign;
  bool relaxEnds = false;

  if (stage == Stage::Relax) {
    ++relaxSteps;
    // Before any increment exists, "small" is judged against the expected increment from the
    // affine stiffness (an upper bound, so the criterion is on the safe side).
    const Real expected = increment > 0 ? increment : K[axis] * gammaTarget;
    const bool ok = maskedError(stress, holdGoal_, mask) < relativeTolerance * expected &&
                    unbalanced < unbalancedTolerance;
    settled_ = ok ? settled_ + 1 : 0;
    if (settled_ >= stepsFor(settleSteps, stepScale)) {
      refStress = stress;
      refDeformation = m.deformation;
      target = refStress;
      rampRate_ = (increment > 0 ? increment : 0.5 * K[axis] * gammaTarget) / stepsFor(rampSteps, stepScale);
      stage = Stage::Ramp;
      settled_ = 0;
      relaxEnds = true;
    }
  } else if (stage == Stage::Ramp) {
    ++rampStepsDone;
    dStrain = strainBetween(refDeformation, m.deformation);
    gamma = strainMeasure();
    const Real reached = sideSign * (target[axis] - refStress[axis]);
    const bool stop = increment > 0 ? reached >= increment : gamma >= gammaTarget;
    if (stop) {
      if (increment > 0) target[axis] = refStress[axis] + sideSign * increment;
      stage = Stage::Hold;
    } else {
      target[axis] += sideSign * rampRate_;
    }
  } else if (stage == Stage::Hold) {
    ++holdSteps;
    const Real inc = std::abs(target[axis] - refStress[axis]);
    const bool ok = maskedError(stress, target, mask) < relativeTolerance * inc && unbalanced < unbalancedTolerance;
    settled_ = ok ? settled_ + 1 : 0;
    if (settled_ >= stepsFor(settleSteps, stepScale)) {
      dStress = stress - refStress;
      dStrain = strainBetween(refDeformation, m.deformation);
      gamma = strainMeasure();
      finishSide();
      // The second side starts where Relax ended: the host puts that state back and this step
      // applies the rates of that step.
      return restorePending_ ? relaxRates_ : Vec6::Zero();
    }
  }
  if (steps > stepsFor(maxSteps, stepScale)) {
    std::ostringstream msg;
    msg << "probe on axis " << kAxisNames[axis] << " did not reach equilibrium within "
        << stepsFor(maxSteps, stepScale) << " steps";
    message = msg.str();
    stage = Stage::Failed;
    done = true;
    return Vec6::Zero();
  }
  Vec6 goal = target;
  for (int I = 0; I < 6; ++I)
    if (!(mask >> I & 1u)) goal[I] = 0;  // held strain: rate 0
  const Vec6 rates = law.perStep(stepScale).rates(goal, mask, stress, K, dt);
  if (relaxEnds) relaxRates_ = rates;
  return rates;
}

}  // namespace trueaniso
