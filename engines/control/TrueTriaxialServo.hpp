#pragma once
// b-controlled true-triaxial servo at constant mean stress (paper section 2.2, Eqs. 8-9).
//
// From the stresses it finds when it starts, the servo moves its goal along the straight stress
// path to the state's (sigma_x, sigma_y, sigma_z) of Eq. (9) — a line of constant b and p when it
// starts on one, as from the isotropic state or from an earlier state of the same path. The goal
// advances only while the specimen follows it (every stress within `followTolerance`), so the
// loading is as fast as the specimen allows and never outruns it. At the end it holds the state
// until every stress is within `stressTolerance` and the unbalanced force is below its tolerance.
// A specimen that cannot carry the state (strain beyond `maxStrain`, or no convergence within
// `maxSteps`) ends the run with status Failed and a message; it never loops forever.
//
// The three shear stresses are servoed too (controlShear, the default), to `shearGoal` (zero: the
// paper's frictionless walls transmit no shear, so the cell's axes are the principal axes), and
// move along the path with the normal stresses. A state is reached when the principal stresses
// and the shear stresses are all within `stressTolerance` (StressGap). With controlShear off the
// cell keeps its shear strains (an orthorhombic cell, whose shear stresses nothing
// holds); a shear goal on such a path is refused.
//
// With feedForward on, the goal's motion is fed forward through the cell's measured tangent
// stiffness (CellServoLaw, TangentRatio): the stress keeps pace with the ramp instead of lagging
// it by pathRate / (gain x tangent ratio), so the goal does not wait for it, and the state is
// held from a stress already at the goal. The goal still advances only while the stress follows
// it, and stops feeding forward while it waits, so a specimen that cannot carry the state
// stalls and fails as without it.
#include <string>

#include "control/CellMeasurement.hpp"
#include "control/CellServoLaw.hpp"
#include "control/StressGap.hpp"
#include "control/TrueTriaxialPath.hpp"
#include "core/Engine.hpp"

namespace trueaniso {

class TrueTriaxialServo : public Engine {
 public:
  enum class Status { Idle, Loading, Holding, Reached, Failed };

  TrueTriaxialState goal;
  Vec3 shearGoal = Vec3::Zero();   // sigma_yz, sigma_xz, sigma_xy at the state (Pa)
  bool controlShear = true;        // servo the shear stresses (else hold the shear strains)
  CellServoLaw law;
  bool feedForward = false;        // feed the goal's motion forward (see above)
  TangentRatio tangent;            // the cell's tangent / affine stiffness, measured while loading
  // The friction of every contact while loading (the paper's 0.5), set on the scene by start():
  // a scene fresh from a probe or from elsewhere may carry another value. The servo owns it as
  // the probe owns kProbeFriction. (update() alone, as the YADE adapter uses it, leaves friction
  // to the host.)
  Real loadingFriction = kLoadingFriction;
  // The per-step settings below (pathRate, the law's gain, the step counts) are per reference
  // step, the step of the reference time step rule (Scene::referenceDt): a step stepScale times
  // longer moves the goal stepScale times as far, closes stepScale times the error, and counts
  // for stepScale steps, so the loading's rate in time, and the state it reaches, do not depend on
  // the rule but by integration error. apply() takes stepScale from the scene; a host that calls
  // update() alone (the YADE adapter) leaves it at 1, its own step being the unit.
  Real stepScale = 1.0;
  Real pathRate = 2.0;             // Pa per (reference) step: the fastest the goal moves along the path
  Real followTolerance = 1000.0;   // Pa
  Real stressTolerance = 500.0;    // Pa: principal and shear stresses, within 0.5 kPa
  Real unbalancedTolerance = 1e-4;  // as reach_state and docs/triaxial.md
  long settleSteps = 200;          // the hold criterion must be met this many steps in a row
  Real maxStrain = 0.05;           // failure: |cell strain since start| on any axis beyond it
  long maxSteps = 3000000;
  // A packing that has lost its stress (a loose packing whose friction was lowered, a cloud not yet
  // in contact): a normal stress below this fraction of its current goal is loaded at the strain
  // rate cap (law.maxStrainRate, an inertial number's), as YADE's PeriTriaxController does far
  // from its goal: the proportional law would take its strain from the affine stiffness of the few
  // contacts left, orders above the packing's own, and creep. A specimen followed along its path
  // (within followTolerance) never comes near it, so no study's loading changes; 0 switches it off.
  Real lostStressFraction = 0.5;
  // Failure: while loading, the specimen has not followed the goal (no progress) for this many
  // steps: it creeps at a stress ratio it cannot exceed.
  long stallSteps = 100000;
  // Failure: held at the state this many steps without meeting the hold criterion (it creeps
  // or oscillates there); a stall while holding is reported, not waited out to maxSteps.
  long holdSteps = 200000;

  // State, readable from Python.
  Status status = Status::Idle;
  std::string message;
  Real progress = 0;               // 0 at the start stresses, 1 at the state
  // Voigt (xx, yy, zz, yz, xz, xy), compression positive.
  Vec6 startStress = Vec6::Zero(), target = Vec6::Zero(), stress = Vec6::Zero();
  Mat3 startDeformation = Mat3::Identity();  // the cell's F when the servo started
  StressGap gap;                   // of the last measurement against the state
  // Largest excursion of each stress beyond its final value in the direction of loading (Pa);
  // <= 0 means it never passed its goal.
  Vec6 overshoot = Vec6::Constant(-1e300);
  Real unbalanced = 0;
  Real lag = 0;                    // largest |stress - goal| now (Pa), the stress-controlled components
  // Steps: run, in a row at the hold criterion, in a row waited for, held, and waited for in all
  // (the goal did not move because a stress was more than followTolerance behind it).
  long steps = 0, settled = 0, stalled = 0, holding = 0, waited = 0;

  void reset() {
    status = Status::Idle;
    message.clear();
    progress = 0;
    steps = settled = stalled = holding = waited = 0;
    lag = 0;
    overshoot = Vec6::Constant(-1e300);
    tangent.reset();
    predicted_.setZero();
    done = false;
    started_ = false;
  }
  // Validates the parameters and sets the loading friction on the scene, before the first force
  // evaluation of the run (the engine list evaluates forces before the servo). Required before
  // apply(), as StressProbe::start.
  void start(Scene& scene);
  void apply(Scene& scene) override;
  // The control logic alone: cell strain rates (Voigt, engineering, extension positive) from a
  // measurement (used by apply and by the YADE adapter). Sets `done` when the state is reached or
  // has failed.
  Vec6 update(const CellMeasurement& m, Real dt);
  std::string name() const override { return "TrueTriaxialServo"; }
  bool readsCellMeasures() const override { return true; }
  // The state's six stresses (Voigt): Eq. (9) on the diagonal, shearGoal off it.
  Vec6 finalStress() const;
  unsigned stressMask() const { return controlShear ? kAllComponents : kNormalComponents; }
  void validate() const;

 private:
  bool started_ = false;
  // A step count given per reference step, in steps of the current length (itself at scale 1).
  long scaled(long n) const;
  // The rates with every lost normal stress (lostStressFraction) loaded at the cap.
  Vec6 recovering(Vec6 rates, unsigned mask, const CellServoLaw& stepLaw) const;
  Vec6 predicted_ = Vec6::Zero();  // the affine stress change of the last rates (TangentRatio)
};

}  // namespace trueaniso
