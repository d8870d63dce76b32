#include "control/StressServo.hpp"

#include "measure/Stress.hpp"

namespace trueaniso {

void StressServo::apply(Scene& s) {
  require((target.array() > 0).all(), "servo target stresses must be > 0 (compression positive)");
  law.validate();
  stress = loveWeberStress(s).diagonal();
  s.cell.strainRate = law.rates(target, stress, affineAxialStiffness(s), s.dt);
  unbalanced = unbalancedForce(s);
  reached = (stress - target).cwiseAbs().maxCoeff() < stressTolerance && unbalanced < unbalancedTolerance;
  if (reached && stopWhenReached) done = true;
}

}  // namespace trueaniso
