#pragma once
// The feedback law shared by the servo and the probe, kept free of any scene so the same law
// drives our cell and, through the YADE adapter, YADE's O.cell.velGrad.
//
// Each axis' strain rate closes a fraction `gain` of the stress error per step, the error being
// turned into a strain through the affine stiffness estimate (an upper bound of the true
// stiffness, so the loop under-corrects and stays monotonic), capped by `maxStrainRate`.
#include <algorithm>

#include "core/Types.hpp"

namespace trueaniso {

struct CellServoLaw {
  Real gain = 0.01;
  Real maxStrainRate = 1.0;  // 1/s

  void validate() const {
    require(gain > 0 && gain <= 1, "servo gain must lie in (0, 1]");
    require(maxStrainRate > 0, "servo maximum strain rate must be > 0");
  }
  // Cell strain rates (extension positive) from stresses and goals (compression positive).
  Vec3 rates(const Vec3& target, const Vec3& stress, const Vec3& stiffness, Real dt) const {
    Vec3 r;
    for (int k = 0; k < 3; ++k) {
      const Real err = target[k] - stress[k];
      const Real v = stiffness[k] > 0 ? -gain * err / (stiffness[k] * dt) : (err > 0 ? -maxStrainRate : maxStrainRate);
      r[k] = std::clamp(v, -maxStrainRate, maxStrainRate);
    }
    return r;
  }
};

}  // namespace trueaniso
