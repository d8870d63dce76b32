#pragma once
// Servo on the cell's stresses to fixed goals (isotropic consolidation, holding a state): a mixed
// stress/strain control of the six components (CellServoLaw), by default every component under
// stress control with the off-diagonal goals at zero, so that the axes of the cell are the
// principal axes of the stress.
#include "control/CellServoLaw.hpp"
#include "control/StressGap.hpp"
#include "core/Engine.hpp"

namespace trueaniso {

class StressServo : public Engine {
 public:
  // Goals per Voigt component (xx, yy, zz, yz, xz, xy): stresses (Pa, compression > 0) for the
  // components in stressMask, engineering strain rates (1/s, extension > 0) for the others.
  Vec6 goal = (Vec6() << 100e3, 100e3, 100e3, 0, 0, 0).finished();
  unsigned stressMask = kAllComponents;
  CellServoLaw law;  // its gain per reference step, as the other controllers' (Scene::stepScale)
  Real stressTolerance = 100.0; // Pa: principal and off-diagonal errors below it count as reached
  Real unbalancedTolerance = 1e-3;
  bool stopWhenReached = false;

  // Last measurement, readable from Python.
  Vec6 stress = Vec6::Zero();
  StressGap gap;
  Real unbalanced = 0;
  bool reached = false;

  void validate() const;
  void apply(Scene& scene) override;
  std::string name() const override { return "StressServo"; }
  bool readsCellMeasures() const override { return true; }
};

}  // namespace trueaniso
