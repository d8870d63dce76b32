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
#include <algorithm>
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
    require(dt > 0, "cell servo: the time step must be > 0 (a TimeStepper runs after the controllers: set scene.dt)");
    Vec6 r;
    for (int k = 0; k < 6; ++k) {
      if (!(stressMask >> k & 1u)) {
        r[k] = goal[k];
        continue;
      }
      const Real err = goal[k] - stress[k];
      const Real v = stiffness[k] > 0 ? -gain * err / (stiffness[k] * dt) : (err > 0 ? -maxStrainRate : maxStrainRate);
      r[k] = std::clamp(v, -maxStrainRate, maxStrainRate);
    }
    return r;
  }
  // The cell's velocity gradient of those rates: symmetric, E_yz = E_zy = rate_yz / 2.
  static Mat3 velocityGradient(const Vec6& rates) { return voigt::gradient(rates); }
};

}  // namespace trueaniso
