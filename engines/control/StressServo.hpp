#pragma once
// Servo on the cell's diagonal stresses: each axis' strain rate is set from its stress error,
// scaled by the affine stiffness estimate so the gain is dimensionless (the fraction of the
// estimated strain gap closed per step), and capped by a maximum strain rate.
// Used for isotropic consolidation; the true-triaxial servo moves its targets along a path.
#include "dynamics/Engine.hpp"

namespace trueaniso {

class StressServo : public Engine {
 public:
  Vec3 target = Vec3::Constant(100e3);  // sigma_x, sigma_y, sigma_z goals (Pa, compression > 0)
  Real gain = 0.01;
  Real maxStrainRate = 1.0;     // 1/s; set from an inertial number by the caller
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
