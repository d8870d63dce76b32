#pragma once
// Directional stress probe (paper section 2.2, Eqs. 10-12) at a held state, on a normal stress
// (x, y, z: E_i, nu_ij) or on a shear stress (yz, xz, xy: G_ij).
//
// start(scene, hold) keeps a snapshot of the whole scene, suppresses sliding (friction `probeFriction`) and
// optionally restrains rotations. Then, step by step:
//  Relax  - hold the starting stresses until equilibrium; this is the reference (stress, cell),
//           so no drift of the state before the probe is counted as its response;
//  Ramp   - raise (or lower, `sign`) the probed stress while the five others are held, until the
//           strain reaches `gammaTarget` (or until `increment` Pa): for a normal probe gamma is
//           Eq. (12) of the normal strain increments, for a shear probe the engineering shear
//           strain increment of the probed component;
//  Hold   - hold those goals until quasi-static equilibrium;
//  Done   - increments, E_i (Eq. 10), nu_ij (Eq. 11) or G_ij are available.
// restore() puts the snapshot back (friction, rotations, tangential forces, cell, positions), so
// every probe starts from the same state.
//
// twoSided: after Relax the probe runs Ramp and Hold with `sign`, then puts the relaxed state back
// and runs them again with -sign; the increments are the half differences of the two sides (a
// central difference about the held state). What the held state does by itself while it is
// probed is the same in both sides, which start from the same relaxed state, and cancels: with
// sliding suppressed a clump packing still moves (bodies with one contact roll on their
// neighbours and spin them up, as the static solve's rattlers cannot), by ~1e-3 of the probe's
// strain over its few hundred steps, which is 1-2 % of its lateral strains (docs/studies/clumps.md
// 5j). The second-order part of the finite increment cancels too. It costs a second Ramp and Hold,
// not a second Relax.
//
// The shear stresses are held (controlShear, the default), as the paper's frictionless walls hold
// them at zero: the probe's strains are then those of the full compliance S = C^-1, E_i = 1/S_ii,
// nu_ij = -S_ji/S_ii, G_ij = 1/S_kk (theory/Orthotropic.hpp). With controlShear off the cell's
// shear strains are held instead (the orthorhombic probe of before) and only x, y, z can be probed.
#include <memory>

#include "control/CellMeasurement.hpp"
#include "control/CellServoLaw.hpp"
#include "core/Engine.hpp"

namespace trueaniso {

class StressProbe : public Engine {
 public:
  enum class Stage { Idle, Relax, Ramp, Hold, Done, Failed };

  int axis = 2;                    // Voigt component: 0, 1, 2 = x, y, z; 3, 4, 5 = yz, xz, xy
  int sign = 1;                    // +1 loads (compression, or a positive shear stress), -1 unloads
  Real gammaTarget = 1e-6;         // strain at which the ramp stops (Eq. 12, or the shear strain)
  Real increment = 0;              // Pa; > 0 replaces the gamma criterion by a fixed increment
  Real probeFriction = kProbeFriction;  // the paper's "sliding suppressed"
  bool restrainRotations = false;
  bool controlShear = true;        // hold the shear stresses (else the shear strains)
  // Hold the five other strains instead of their stresses: the probe then measures the
  // stiffness C_kk (d sigma_k / d eps_k with every other strain zero) where the stress-held probe
  // measures 1/S_kk. The two differ by the packing's couplings between components (0.2 % measured
  // between G_yz and C_44 of a 300-sphere packing); the static solve gives both.
  bool holdOtherStrains = false;
  bool twoSided = false;           // a loading and an unloading side from one relaxed state (above)
  // The gain and the step counts below are per reference step (Scene::referenceDt), as the
  // servo's: a step stepScale reference steps long closes stepScale times the error, ramps
  // stepScale times as far and counts for stepScale steps, so that the probe takes the same time,
  // and measures the same modulus but by integration error, under any time step rule. apply()
  // takes stepScale from the scene; a host that calls update() alone (the YADE adapter) leaves it
  // at 1, its own step being the unit.
  Real stepScale = 1.0;
  CellServoLaw law{0.03, 1.0};     // gain 0.03: docs/speed-vs-error.md
  long rampSteps = 300;            // the ramp's expected length, sets its rate
  Real relativeTolerance = 2e-3;   // stress error allowed, as a fraction of the increment
  Real unbalancedTolerance = 1e-5;
  long settleSteps = 100;          // criteria must hold this many steps in a row
  long maxSteps = 2000000;

  // Results, readable from Python. Stresses and strains are Voigt (xx, yy, zz, yz, xz, xy),
  // compression positive, engineering shear strains; strains are taken from the reference cell.
  Stage stage = Stage::Idle;
  std::string message;
  Vec6 refStress = Vec6::Zero();
  Mat3 refDeformation = Mat3::Identity();
  Vec6 target = Vec6::Zero(), stress = Vec6::Zero();
  Vec6 dStress = Vec6::Zero(), dStrain = Vec6::Zero();
  // A two-sided probe's sides (the first with `sign`, the second with -sign); dStress and dStrain
  // are (first - second) / 2. A one-sided probe's first side is its result, its second zero.
  Vec6 dStressFirst = Vec6::Zero(), dStrainFirst = Vec6::Zero();
  Vec6 dStressSecond = Vec6::Zero(), dStrainSecond = Vec6::Zero();
  int side = 0;                    // 0: the first side (or Relax), 1: the second
  Real gamma = 0, unbalanced = 0;
  long steps = 0, relaxSteps = 0, rampStepsDone = 0, holdSteps = 0;

  // `hold`: the stresses of the held state (the servo's goal, Voigt), which Relax holds.
  void start(Scene& scene, const Vec6& hold);
  void restore(Scene& scene) const;
  void apply(Scene& scene) override;
  // The control logic alone, for a host that snapshots and sets friction itself (the YADE
  // adapter): begin() checks the parameters and resets the stages, update() returns the cell's
  // engineering strain rates (Voigt, extension positive). A two-sided probe through update()
  // alone needs the host to keep its state as it was when Relax ended (the step whose update()
  // turned the stage to Ramp, before that step's rates act) and, when update() returns with
  // restorePending(), to put that state back before it applies the rates returned (those of that
  // step), then call restored(). apply() does this on the scene.
  void begin(const Vec6& hold);
  Vec6 update(const CellMeasurement& m, Real dt);
  bool restorePending() const { return restorePending_; }
  void restored() { restorePending_ = false; }
  std::string name() const override { return "StressProbe"; }
  bool readsCellMeasures() const override { return true; }

  unsigned stressMask() const {
    if (holdOtherStrains) return 1u << axis;
    return controlShear ? kAllComponents : kNormalComponents;
  }
  bool shearProbe() const { return axis >= 3; }
  Real modulus() const { return dStress[axis] / dStrain[axis]; }                 // E_i (Eq. 10) or G_ij
  Real youngModulus() const { return modulus(); }
  Real poissonRatio(int j) const { return -dStrain[j] / dStrain[axis]; }         // Eq. (11)

 private:
  Real strainMeasure() const;      // gamma of the current dStrain
  void finishSide();
  std::shared_ptr<Scene> snapshot_;
  std::shared_ptr<Scene> relaxed_;  // the scene as Relax ended (two-sided, apply())
  Vec6 relaxRates_ = Vec6::Zero();  // the rates of the step Relax ended
  bool restorePending_ = false;
  Vec6 holdGoal_ = Vec6::Zero();
  Real rampRate_ = 0;
  long settled_ = 0;
};

}  // namespace trueaniso
