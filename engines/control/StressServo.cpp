#include "control/StressServo.hpp"

#include "control/CellMeasurement.hpp"

namespace trueaniso {

void StressServo::validate() const {
  require(stressMask <= kAllComponents, "servo stress mask must lie in [0, 63] (bits xx yy zz yz xz xy)");
  require(goal.allFinite(), "servo goals must be finite numbers");
  for (int k = 0; k < 3; ++k)
    if (stressMask >> k & 1u) require(goal[k] > 0, "servo target stresses must be > 0 (compression positive)");
  for (int k = 0; k < 6; ++k)
    if (!(stressMask >> k & 1u))
      require(std::abs(goal[k]) <= law.maxStrainRate,
              "a strain-controlled component's goal is its strain rate: it must not exceed the maximum strain rate");
  require(stressTolerance > 0, "servo stress tolerance must be > 0");
  law.validate();
}

void StressServo::apply(Scene& s) {
  validate();
  const CellMeasurement m = CellMeasurement::of(s);
  stress = m.stress;
  s.cell.velGrad =
      CellServoLaw::velocityGradient(law.perStep(s.stepScale()).rates(goal, stressMask, m.stress, m.stiffness, s.dt));
  unbalanced = m.unbalanced;
  gap = stressGap(stress, goal, stressMask);
  reached = gap.error() < stressTolerance && unbalanced < unbalancedTolerance;
  if (reached && stopWhenReached) done = true;
}

}  // namespace trueaniso
