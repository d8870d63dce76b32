#pragma once
// How far a measured stress is from a goal, in the terms a state is accepted in (both within
// 0.5 kPa by default): each principal stress against the goal's principal stress (both sorted, largest first)
// and each component under stress control against its goal. Both are needed: at an isotropic goal
// off-diagonal stresses of 0.4 kPa each leave every component within 0.5 kPa and still move the
// principal stresses by up to 0.8 kPa; a principal error alone would accept a rotated state.
#include <algorithm>

#include "control/CellServoLaw.hpp"
#include "measure/Stress.hpp"

namespace trueaniso {

struct StressGap {
  Vec3 principal = Vec3::Zero();      // of the measured stress, largest first
  Vec3 goalPrincipal = Vec3::Zero();  // of the goal (all six components under stress control)
  // max |principal_k - goalPrincipal_k|; 0 when a shear component is not under stress control
  // (its stress is then not a goal, and neither are the principal values).
  Real principalError = 0;
  Real componentError = 0;            // max |stress_I - goal_I| over the stress-controlled components
  Real maxShear = 0;                  // largest |off-diagonal| of the measured stress

  Real error() const { return std::max(principalError, componentError); }
};

inline StressGap stressGap(const Vec6& stress, const Vec6& goal, unsigned stressMask) {
  StressGap g;
  g.principal = principalStresses(voigt::stressTensor(stress));
  g.maxShear = stress.tail<3>().cwiseAbs().maxCoeff();
  for (int I = 0; I < 6; ++I)
    if (stressMask >> I & 1u) g.componentError = std::max(g.componentError, std::abs(stress[I] - goal[I]));
  if ((stressMask & kAllComponents) == kAllComponents) {
    g.goalPrincipal = principalStresses(voigt::stressTensor(goal));
    g.principalError = (g.principal - g.goalPrincipal).cwiseAbs().maxCoeff();
  }
  return g;
}

}  // namespace trueaniso
