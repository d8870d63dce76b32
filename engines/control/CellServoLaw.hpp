#pragma once
// The feedback law shared by the servos and the probe, kept free of any scene so the same law
// drives our cell and, through the YADE adapter, YADE's O.cell.velGrad.
//
// A mixed stress/strain control per Voigt component, as YADE's PeriTriaxController's stressMask but
// for all six (xx, yy, zz, yz, xz, xy): a component under stress control closes a fraction `gain`
// of its stress error per step, the error turned into a strain through the affine stiffness
// estimate (an upper bound of the true stiffness, so the loop under-corrects and stays
// monotonic), capped by `maxStrainRate`; a component under strain control takes the strain rate
// given as its goal (0 holds it). The rates are engineering strain rates, extension positive; the
// cell's velocity gradient is their symmetric tensor (no spin: the cell's axes stay the frame the
// stresses are given in).
//
// A goal that moves (a servo's ramp) can also be fed forward: the strain rate that moves the
// stress at the goal's own rate through the cell's tangent stiffness, ratio x affine, where the
// ratio is measured on the cell itself (TangentRatio). Proportional control alone follows a ramp
// of rate r (Pa per step) a lag r / (gain x ratio) behind; with the ramp fed forward through the
// measured tangent, the proportional term corrects only what that estimate misses.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/Types.hpp"
#include "core/Voigt.hpp"

namespace trueaniso {

// Bits of a stress mask: bit I set = Voigt component I under stress control.
constexpr unsigned kNormalComponents = 0x07;  // xx, yy, zz
constexpr unsigned kShearComponents = 0x38;   // yz, xz, xy
constexpr unsigned kAllComponents = 0x3F;

struct CellServoLaw {
  Real gain = 0.01;
  Real maxStrainRate = 1.0;  // 1/s

  void validate() const {
    require(gain > 0 && gain <= 1, "servo gain must lie in (0, 1]");
    require(maxStrainRate > 0, "servo maximum strain rate must be > 0");
  }
  // Engineering strain rates (extension positive) from the goals: stresses (compression
  // positive) for the components in `stressMask`, strain rates for the others.
  Vec6 rates(const Vec6& goal, unsigned stressMask, const Vec6& stress, const Vec6& stiffness, Real dt) const {
    return rates(goal, stressMask, stress, stiffness, dt, Vec6::Zero(), Vec6::Ones());
  }
  // The same with the goals' own rates (Pa/s, compression positive) fed forward through the
  // tangent stiffness tangentRatio x stiffness: per stress-controlled component
  //   rate = -(gain x error / dt + goalRate / tangentRatio) / stiffness,
  // capped by maxStrainRate. tangentRatio must lie in (0, 1] where goalRate is not zero.
  Vec6 rates(const Vec6& goal, unsigned stressMask, const Vec6& stress, const Vec6& stiffness, Real dt,
             const Vec6& goalRate, const Vec6& tangentRatio) const {
    require(dt > 0, "cell servo: the time step must be > 0 (a TimeStepper runs after the controllers: set scene.dt)");
    Vec6 r;
    for (int k = 0; k < 6; ++k) {
      if (!(stressMask >> k & 1u)) {
        r[k] = goal[k];
        continue;
      }
      const Real err = goal[k] - stress[k];
      Real v = stiffness[k] > 0 ? -gain * err / (stiffness[k] * dt) : (err > 0 ? -maxStrainRate : maxStrainRate);
      // Added only where the goal moves: without a goal rate this is the proportional law to the bit.
      if (goalRate[k] != 0 && stiffness[k] > 0) v -= goalRate[k] / (tangentRatio[k] * stiffness[k]);
      r[k] = std::clamp(v, -maxStrainRate, maxStrainRate);
    }
    return r;
  }
  // The cell's velocity gradient of those rates: symmetric, E_yz = E_zy = rate_yz / 2.
  static Mat3 velocityGradient(const Vec6& rates) { return voigt::gradient(rates); }
  // The law of a controller whose step is stepScale reference steps (Scene::stepScale): the gain,
  // a fraction of the error closed per reference step, closes stepScale times that a step (capped
  // at the whole error), so the error closes at the same rate in time under any time step rule.
  CellServoLaw perStep(Real stepScale) const {
    CellServoLaw l = *this;
    if (stepScale != 1.0) l.gain = std::min(1.0, gain * stepScale);
    return l;
  }
};

// A count of reference steps (a hold, a ramp, a limit) in steps that are stepScale reference steps
// long: the same time, at least one step. At scale 1 the count itself.
inline long stepsFor(long referenceSteps, Real stepScale) {
  return stepScale == 1.0 ? referenceSteps
                          : std::max(1L, std::lround(static_cast<Real>(referenceSteps) / stepScale));
}

// The cell's tangent stiffness as a fraction of its affine estimate, per Voigt component, measured
// on the cell's own response: the stress change it showed against the stress change the affine
// stiffness predicted for the strain it was given, both summed with exponentially fading weights
// (memory `memory` steps). The ratio of the two sums is the least-squares slope of the stress
// against the predicted stress through the origin; over a ramp both telescope, so the stress's
// fluctuations enter once, not once per step. Where the cell has not been strained enough to say
// (the predicted sum under `minPredicted` Pa, or the two of opposite signs) the ratio is 1, the
// affine bound: a feed-forward through it under-feeds, never over-feeds. Clamped to [floor, 1]:
// the affine stiffness is an upper bound, and below `floor` the feed-forward would drive the
// cell at its maximum rate for a stress that does not come.
struct TangentRatio {
  Real memory = 1000;        // steps
  Real floor = 0.05;
  Real minPredicted = 500;   // Pa

  Vec6 measuredSum = Vec6::Zero(), predictedSum = Vec6::Zero();
  Vec6 lastStress = Vec6::Zero();
  bool primed = false;

  void reset() {
    measuredSum.setZero();
    predictedSum.setZero();
    primed = false;
  }
  // One step: the stress measured now and the stress change the affine stiffness predicted for
  // the strain applied since the last call (-stiffness x rate x dt: compression positive).
  void observe(const Vec6& stress, const Vec6& predictedChange) {
    const Real keep = 1.0 - 1.0 / memory;
    if (primed) {
      measuredSum = keep * measuredSum + (stress - lastStress);
      predictedSum = keep * predictedSum + predictedChange;
    }
    lastStress = stress;
    primed = true;
  }
  Vec6 ratio() const {
    Vec6 r = Vec6::Ones();
    for (int k = 0; k < 6; ++k)
      if (std::abs(predictedSum[k]) >= minPredicted && measuredSum[k] * predictedSum[k] > 0)
        r[k] = std::clamp(measuredSum[k] / predictedSum[k], floor, 1.0);
    return r;
  }
  void validate() const {
    require(memory >= 1 && floor > 0 && floor <= 1 && minPredicted >= 0,
            "tangent ratio: memory must be >= 1 step, floor in (0, 1], minPredicted >= 0");
  }
};

}  // namespace trueaniso
