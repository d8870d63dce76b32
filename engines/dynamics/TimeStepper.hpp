#pragma once
// Time step from the current contact stiffnesses. For each body the translational stiffness is
// bounded by the sum of its contacts' k_n, the rotational one by the sum of k_s arm^2; the step is
// a safety fraction of the smallest sqrt(mass/stiffness), as YADE's GlobalStiffnessTimeStepper.
#include "core/Engine.hpp"

namespace trueaniso {

class TimeStepper : public Engine {
 public:
  TimeStepper() { every = 10; }
  Real safety = 0.5;
  // Upper bound used while there are few or no contacts (a loose gas would otherwise get a huge
  // step right before its first collisions); the caller sets it from the expected contact force.
  Real maxDt = 1.0;

  void apply(Scene& scene) override;
  std::string name() const override { return "TimeStepper"; }

  // sqrt(m/K) bound over bodies, without the safety factor.
  static Real stiffnessBound(const Scene& scene);
  // Largest step for which every single contact, alone between its two bodies, is stable
  // (2/omega of the pair). A step above it cannot be stable and is refused.
  static Real criticalPairStep(const Scene& scene);
};

}  // namespace trueaniso
