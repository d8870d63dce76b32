#pragma once
// Particle material of the paper's Table 1 and the coefficients of Eqs. (5)-(6).
#include <cmath>

#include "core/Types.hpp"

namespace trueaniso {

// The paper's friction coefficient during stress probes: sliding suppressed (section 2.2). The one
// place this number is written; the probe, the static solve and Python (engines.PROBE_FRICTION)
// read it here.
constexpr Real kProbeFriction = 1e23;
// The paper's friction coefficient while consolidating and loading along the stress paths.
constexpr Real kLoadingFriction = 0.5;

struct Material {
  Real shearModulus = 18e9;  // G_g (Pa)
  Real poisson = 0.15;       // nu_g
  Real density = 2500.0;     // kg/m^3
  Real friction = kLoadingFriction;  // mu, switchable at run time (kProbeFriction while probing)
  // Rolling resistance (contact/HertzMindlin.hpp, docs/rolling.md), not in the paper and off by
  // default: k_r = rollingStiffness k_s rbar^2 (Iwashita & Oda's beta), the rolling moment capped
  // at rollingFriction rbar N (eta_r). rollingStiffness 0 turns the whole sub-model off.
  Real rollingStiffness = 0.0;  // beta
  Real rollingFriction = 0.0;   // eta_r

  bool rolling() const { return rollingStiffness > 0; }

  void validate() const {
    require(shearModulus > 0, "shear modulus must be > 0");
    require(poisson > -1.0 && poisson < 0.5, "Poisson's ratio must lie in (-1, 0.5)");
    require(density > 0, "density must be > 0");
    require(friction >= 0, "friction coefficient must be >= 0");
    // Written so that NaN fails too (every comparison with NaN is false).
    require(rollingStiffness >= 0 && std::isfinite(rollingStiffness),
            "rolling stiffness factor beta must be a finite number >= 0 (0: no rolling resistance)");
    require(rollingFriction >= 0 && std::isfinite(rollingFriction),
            "rolling friction eta_r must be a finite number >= 0");
  }
  // E* = G/(1-nu): the contact modulus of two identical spheres, E/(2(1-nu^2)).
  Real contactModulus() const { return shearModulus / (1.0 - poisson); }
  // C_n of Eq. (5): (3/4) [8G/(3(1-nu))]^(2/3), equal to (3 E*^2)^(1/3).
  Real Cn() const { return 0.75 * std::pow(8.0 * shearModulus / (3.0 * (1.0 - poisson)), 2.0 / 3.0); }
  // C_s of Eq. (6): 2 [3 G^2 (1-nu)]^(1/3) / (2-nu).
  Real Cs() const {
    return 2.0 * std::cbrt(3.0 * shearModulus * shearModulus * (1.0 - poisson)) / (2.0 - poisson);
  }
  // k_s/k_n = C_s/C_n = 2(1-nu)/(2-nu) for every contact of this law.
  Real stiffnessRatio() const { return 2.0 * (1.0 - poisson) / (2.0 - poisson); }
};

}  // namespace trueaniso
