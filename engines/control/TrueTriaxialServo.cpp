#include "control/TrueTriaxialServo.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>


namespace trueaniso {

void TrueTriaxialServo::validate() const {
  goal.validate();
  law.validate();
  require(pathRate > 0 && stressTolerance > 0 && followTolerance > 0 && maxStrain > 0,
          "servo tolerances and path rate must be > 0");
  require(std::isfinite(loadingFriction) && loadingFriction > 0,
          "servo: the loading friction must be a finite number > 0");
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
  s.cell.strainRate = update(CellMeasurement::of(s), s.dt);
}

Vec3 TrueTriaxialServo::update(const CellMeasurement& m, Real dt) {
  if (status == Status::Reached || status == Status::Failed) {
    done = true;
    return Vec3::Zero();
  }
  stress = m.stress;
  unbalanced = m.unbalanced;
  if (status == Status::Idle) {
    validate();
    startStress = stress;
    target = stress;
    startStrain = m.strain;
    status = Status::Loading;
  }
  ++steps;
  const Vec3 final = goal.stresses();
  if (status == Status::Loading) {
    if ((stress - target).cwiseAbs().maxCoeff() < followTolerance) {
      const Real length = (final - startStress).cwiseAbs().maxCoeff();
      progress = length > 0 ? std::min(1.0, progress + pathRate / length) : 1.0;
      stalled = 0;
      if (progress >= 1.0) status = Status::Holding;
    } else {
      ++stalled;
    }
  }
  target = startStress + progress * (final - startStress);
  for (int k = 0; k < 3; ++k) {
    const Real dir = final[k] >= startStress[k] ? 1.0 : -1.0;
    overshoot[k] = std::max(overshoot[k], dir * (stress[k] - final[k]));
  }

  const Vec3 strain = m.strain - startStrain;
  if (status == Status::Holding) ++holding;
  if (strain.cwiseAbs().maxCoeff() > maxStrain || steps > maxSteps || stalled > stallSteps ||
      holding > holdSteps) {
    std::ostringstream msg;
    msg << "state b = " << goal.b << ", sigma_z = " << goal.sigmaZ / 1e3 << " kPa not reached: ";
    if (steps > maxSteps) msg << "no equilibrium within " << maxSteps << " steps";
    else if (holding > holdSteps)
      msg << "held " << holdSteps << " steps without settling (stress off by "
          << (stress - final).cwiseAbs().maxCoeff() << " Pa, unbalanced force " << unbalanced << ")";
    else if (stalled > stallSteps)
      msg << "the specimen stopped following the path for " << stallSteps << " steps (it fails, at "
          << 100 * progress << " % of the path)";
    else msg << "strain " << strain.cwiseAbs().maxCoeff() << " beyond " << maxStrain << " (the specimen fails)";
    msg << " at stresses (" << stress.x() / 1e3 << ", " << stress.y() / 1e3 << ", " << stress.z() / 1e3 << ") kPa";
    message = msg.str();
    status = Status::Failed;
    done = true;
    return Vec3::Zero();
  }
  if (status == Status::Holding) {
    const bool ok = (stress - final).cwiseAbs().maxCoeff() < stressTolerance && unbalanced < unbalancedTolerance;
    settled = ok ? settled + 1 : 0;
    if (settled >= settleSteps) {
      status = Status::Reached;
      done = true;
      return Vec3::Zero();
    }
  }
  return law.rates(target, stress, m.stiffness, dt);
}

}  // namespace trueaniso
