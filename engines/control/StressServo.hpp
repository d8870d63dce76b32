#pragma once
// Servo on the cell's diagonal stresses to fixed goals (isotropic consolidation, holding a state).
#include "control/CellServoLaw.hpp"
#include "core/Engine.hpp"

namespace trueaniso {

class StressServo : public Engine {
 public:
  Vec3 target = Vec3::Constant(100e3);  // sigma_x, sigma_y, sigma_z goals (Pa, compression > 0)
  CellServoLaw law;
  Real stressTolerance = 100.0; // Pa: |sigma_k - goal| below it counts as reached
  Real unbalancedTolerance = 1e-3;
  bool stopWhenReached = false;

  // Last measurement, readable from Python.
  Vec3 stress = Vec3::Zero();
  Real unbalanced = 0;
  bool reached = false;

  void apply(Scene& scene) override;
  std::string name() const override { return "StressServo"; }
};

}  // namespace trueaniso
