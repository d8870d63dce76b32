#pragma once
// The strain rate of a given inertial number, I = rate d50 sqrt(rho / p) (GDR MiDi 2004; I <= 1e-3:
// quasi-static): the cap on the cell's strain rate while a servo loads a packing (triaxial.reach_state
// through dem.strain_rate_for_inertial_number, the YADE plugin's TrueTriaxialServo).
#include <cmath>

#include "core/Types.hpp"

namespace trueaniso {

inline Real strainRateForInertialNumber(Real inertialNumber, Real d50, Real density, Real pressure) {
  require(std::isfinite(inertialNumber) && inertialNumber > 0, "the inertial number must be a finite number > 0");
  require(std::isfinite(d50) && d50 > 0 && std::isfinite(density) && density > 0 && std::isfinite(pressure) &&
              pressure > 0,
          "the inertial number's strain rate needs a diameter, a density and a pressure, each finite and > 0");
  return inertialNumber / (d50 * std::sqrt(density / pressure));
}

}  // namespace trueaniso
