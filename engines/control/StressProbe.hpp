#pragma once
// Directional stress probe (paper section 2.2, Eqs. 10-12) at a held state.
//
// start(scene, hold) keeps a snapshot of the whole scene, suppresses sliding (friction `probeFriction`) and
// optionally restrains rotations. Then, step by step:
//  Relax  - hold the starting stresses until equilibrium; this is the reference (stress, strain),
//           so no drift of the state before the probe is counted as its response;
//  Ramp   - raise (or lower, `sign`) sigma_i while the two other stresses are held, until the
//           shear strain gamma of Eq. (12) reaches `gammaTarget` (or until `increment` Pa);
//  Hold   - hold those goals until quasi-static equilibrium;
//  Done   - increments, E_i (Eq. 10) and nu_ij (Eq. 11) are available.
// restore() puts the snapshot back (friction, rotations, tangential forces, cell, positions), so
// the x, y and z probes start from the same state.
#include <memory>

#include "control/CellMeasurement.hpp"
#include "control/CellServoLaw.hpp"
#include "core/Engine.hpp"

namespace trueaniso {

class StressProbe : public Engine {
 public:
  enum class Stage { Idle, Relax, Ramp, Hold, Done, Failed };

  int axis = 2;                    // 0, 1, 2 = x, y, z
  int sign = 1;                    // +1 loads (compression), -1 unloads
  Real gammaTarget = 1e-6;         // Eq. (12) at which the ramp stops
  Real increment = 0;              // Pa; > 0 replaces the gamma criterion by a fixed increment
  Real probeFriction = kProbeFriction;  // the paper's "sliding suppressed"
  bool restrainRotations = false;
  CellServoLaw law{0.03, 1.0};     // gain 0.03: docs/speed-vs-error.md
  long rampSteps = 300;            // the ramp's expected length, sets its rate
  Real relativeTolerance = 2e-3;   // stress error allowed, as a fraction of the increment
  Real unbalancedTolerance = 1e-5;
  long settleSteps = 100;          // criteria must hold this many steps in a row
  long maxSteps = 2000000;

  // Results, readable from Python.
  Stage stage = Stage::Idle;
  std::string message;
  Vec3 refStress = Vec3::Zero(), refStrain = Vec3::Zero();
  Vec3 target = Vec3::Zero(), stress = Vec3::Zero();
  Vec3 dStress = Vec3::Zero(), dStrain = Vec3::Zero();
  Real gamma = 0, unbalanced = 0;
  long steps = 0, relaxSteps = 0, rampStepsDone = 0, holdSteps = 0;

  // `hold`: the stresses of the held state (the servo's goal), which Relax holds.
  void start(Scene& scene, const Vec3& hold);
  void restore(Scene& scene) const;
  void apply(Scene& scene) override;
  // The control logic alone, for a host that snapshots and sets friction itself (the YADE
  // adapter): begin() resets the stages, update() returns the cell strain rates.
  void begin(const Vec3& hold);
  Vec3 update(const CellMeasurement& m, Real dt);
  std::string name() const override { return "StressProbe"; }

  Real youngModulus() const { return dStress[axis] / dStrain[axis]; }           // Eq. (10)
  Real poissonRatio(int j) const { return -dStrain[j] / dStrain[axis]; }         // Eq. (11)

 private:
  std::shared_ptr<Scene> snapshot_;
  Vec3 holdGoal_ = Vec3::Zero();
  Real rampRate_ = 0;
  long settled_ = 0;
};

}  // namespace trueaniso
