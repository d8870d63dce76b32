#include "control/StressServo.hpp"

#include <algorithm>
#include <cmath>

#include "measure/Stress.hpp"

namespace trueaniso {

void StressServo::apply(Scene& s) {
  require((target.array() > 0).all(), "servo target stresses must be > 0 (compression positive)");
  require(gain > 0 && gain <= 1, "servo gain must lie in (0, 1]");
  require(maxStrainRate > 0, "servo maximum strain rate must be > 0");
  stress = loveWeberStress(s).diagonal();
  const Vec3 K = affineAxialStiffness(s);
  Vec3 rate;
  for (int k = 0; k < 3; ++k) {
    const Real err = target[k] - stress[k];
    // Extension is positive for the cell, compression positive for stress: a stress below its
    // goal needs a negative (shrinking) rate.
    Real r = K[k] > 0 ? -gain * err / (K[k] * s.dt) : (err > 0 ? -maxStrainRate : maxStrainRate);
    rate[k] = std::clamp(r, -maxStrainRate, maxStrainRate);
  }
  s.cell.strainRate = rate;
  unbalanced = unbalancedForce(s);
  reached = (stress - target).cwiseAbs().maxCoeff() < stressTolerance && unbalanced < unbalancedTolerance;
  if (reached && stopWhenReached) done = true;
}

}  // namespace trueaniso
