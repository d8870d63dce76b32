#include "control/RadiusExpansion.hpp"

#include <algorithm>
#include <cmath>

#include "measure/Stress.hpp"

namespace trueaniso {

void RadiusExpansion::apply(Scene& s) {
  require(targetPressure > 0, "radius expansion target pressure must be > 0");
  require(gain > 0 && gain <= 1, "radius expansion gain must lie in (0, 1]");
  require(!s.hasClumps(), "radius expansion applies to single spheres");
  const int nb = s.bodies.size();
  if (base_.size() != static_cast<size_t>(nb)) {
    base_ = s.members.radius;
    scale = 1.0;
  }
  pressure = loveWeberStress(s).trace() / 3.0;
  const Real K = affineStiffness(s).head<3>().mean();
  const Real err = targetPressure - pressure;
  // Growing radii by d ln r is, for the contacts, an isotropic affine compression of d ln r.
  Real rate = K > 0 ? gain * err / (K * s.dt) : (err > 0 ? maxGrowthRate : -maxGrowthRate);
  rate = std::clamp(rate, -maxGrowthRate, maxGrowthRate);
  const Real grow = 1.0 + rate * s.dt;
  scale *= grow;
  for (int b = 0; b < nb; ++b) s.setSphereRadius(b, scale * base_[b]);
  for (Real& r : s.contacts.rbar) r *= grow;  // Eq. (7) is homogeneous in the radii
  unbalanced = unbalancedForce(s);
  reached = std::abs(err) < stressTolerance && unbalanced < unbalancedTolerance;
  if (reached && stopWhenReached) done = true;
}

}  // namespace trueaniso
