#include "control/TrueTriaxialServo.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>


namespace trueaniso {

void TrueTriaxialServo::validate() const {
  goal.validate();
  law.validate();
  require(shearGoal.allFinite(), "servo: the shear stress goals must be finite numbers");
  require(controlShear || shearGoal.isZero(),
          "servo: shear stress goals given on a path that holds the cell's shear strains (controlShear off): "
          "nothing would servo them");
  require(pathRate > 0 && stressTolerance > 0 && followTolerance > 0 && maxStrain > 0,
          "servo tolerances and path rate must be > 0");
  require(unbalancedTolerance > 0 && settleSteps >= 1 && maxSteps >= 1 && stallSteps >= 1 && holdSteps >= 1,
          "servo: the unbalanced force tolerance must be > 0 and the step counts >= 1");
  require(lostStressFraction >= 0 && lostStressFraction < 1, "servo: the lost-stress fraction must lie in [0, 1)");
  require(std::isfinite(stepScale) && stepScale > 0, "servo: the step scale must be a finite number > 0");
  require(std::isfinite(loadingFriction) && loadingFriction > 0,
          "servo: the loading friction must be a finite number > 0");
  tangent.validate();
}

void TrueTriaxialServo::start(Scene& s) {
  reset();
  validate();
  s.material.friction = loadingFriction;
  started_ = true;
}

void TrueTriaxialServo::apply(Scene& s) {
  if (status == Status::Reached || status == Status::Failed) {
    done = true;
    return;
  }
  if (!started_) throw InputError("TrueTriaxialServo: call start(scene) before running it");
  stepScale = s.stepScale();
  s.cell.velGrad = CellServoLaw::velocityGradient(update(CellMeasurement::of(s), s.dt));
}

long TrueTriaxialServo::scaled(long n) const { return stepsFor(n, stepScale); }

Vec6 TrueTriaxialServo::finalStress() const {
  // Fixed-size halves rather than the comma initialiser, whose run-time-sized blocks GCC 12 warned
  // about on the x86-64-v3 build (a 256-bit load of a Vec3, which Eigen never executes).
  Vec6 f;
  f.head<3>() = goal.stresses();
  f.tail<3>() = shearGoal;
  return f;
}

Vec6 TrueTriaxialServo::update(const CellMeasurement& m, Real dt) {
  if (status == Status::Reached || status == Status::Failed) {
    done = true;
    return Vec6::Zero();
  }
  stress = m.stress;
  unbalanced = m.unbalanced;
  if (status == Status::Idle) {
    validate();
    startStress = stress;
    target = stress;
    startDeformation = m.deformation;
    status = Status::Loading;
    tangent.reset();
    predicted_.setZero();
  }
  if (feedForward) tangent.observe(stress, predicted_);
  ++steps;
  const unsigned mask = stressMask();
  Vec6 final = finalStress();
  // Components not under stress control are no goal: the path and its checks leave them out.
  for (int k = 0; k < 6; ++k)
    if (!(mask >> k & 1u)) final[k] = startStress[k];
  Real follow = 0;
  for (int k = 0; k < 6; ++k)
    if (mask >> k & 1u) follow = std::max(follow, std::abs(stress[k] - target[k]));
  lag = follow;
  const Vec6 previousTarget = target;
  if (status == Status::Loading) {
    if (follow < followTolerance) {
      const Real length = (final - startStress).cwiseAbs().maxCoeff();
      progress = length > 0 ? std::min(1.0, progress + pathRate * stepScale / length) : 1.0;
      stalled = 0;
      if (progress >= 1.0) status = Status::Holding;
    } else {
      ++stalled;
      ++waited;
    }
  }
  target = startStress + progress * (final - startStress);
  for (int k = 0; k < 6; ++k) {
    const Real dir = final[k] >= startStress[k] ? 1.0 : -1.0;
    overshoot[k] = std::max(overshoot[k], dir * (stress[k] - final[k]));
  }
  gap = stressGap(stress, final, mask);

  const Vec6 strain = strainBetween(startDeformation, m.deformation);
  if (status == Status::Holding) ++holding;
  const long maxRun = scaled(maxSteps), maxStall = scaled(stallSteps), maxHold = scaled(holdSteps);
  if (strain.cwiseAbs().maxCoeff() > maxStrain || steps > maxRun || stalled > maxStall || holding > maxHold) {
    std::ostringstream msg;
    msg << "state b = " << goal.b << ", sigma_z = " << goal.sigmaZ / 1e3 << " kPa not reached: ";
    if (steps > maxRun) msg << "no equilibrium within " << maxRun << " steps";
    else if (holding > maxHold)
      msg << "held " << maxHold << " steps without settling (stress off by "
          << gap.error() << " Pa, unbalanced force " << unbalanced << ")";
    else if (stalled > maxStall)
      msg << "the specimen stopped following the path for " << maxStall << " steps (it fails, at "
          << 100 * progress << " % of the path)";
    else msg << "strain " << strain.cwiseAbs().maxCoeff() << " beyond " << maxStrain << " (the specimen fails)";
    msg << " at stresses (" << stress[0] / 1e3 << ", " << stress[1] / 1e3 << ", " << stress[2] / 1e3
        << ") kPa, largest shear stress " << gap.maxShear / 1e3 << " kPa";
    message = msg.str();
    status = Status::Failed;
    done = true;
    return Vec6::Zero();
  }
  if (status == Status::Holding) {
    const bool ok = gap.error() < stressTolerance && unbalanced < unbalancedTolerance;
    settled = ok ? settled + 1 : 0;
    if (settled >= scaled(settleSteps)) {
      status = Status::Reached;
      done = true;
      return Vec6::Zero();
    }
  }
  Vec6 goalNow = target;
  for (int k = 0; k < 6; ++k)
    if (!(mask >> k & 1u)) goalNow[k] = 0;  // held shear strains: rate 0
  // The gain closes its fraction of the error per reference step (capped at the whole error).
  const CellServoLaw stepLaw = law.perStep(stepScale);
  if (!feedForward) return recovering(stepLaw.rates(goalNow, mask, stress, m.stiffness, dt), mask, stepLaw);
  // The goal's rate this step: zero while it waits and once it is held.
  const Vec6 goalRate = (target - previousTarget) / dt;
  const Vec6 r = recovering(stepLaw.rates(goalNow, mask, stress, m.stiffness, dt, goalRate, tangent.ratio()), mask,
                            stepLaw);
  predicted_ = -m.stiffness.cwiseProduct(r) * dt;
  return r;
}

Vec6 TrueTriaxialServo::recovering(Vec6 r, unsigned mask, const CellServoLaw& stepLaw) const {
  for (int k = 0; k < 3; ++k)
    if ((mask >> k & 1u) && target[k] > 0 && stress[k] < lostStressFraction * target[k]) r[k] = -stepLaw.maxStrainRate;
  return r;
}

}  // namespace trueaniso
