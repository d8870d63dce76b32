#pragma once
// The contact law's constants for a contact between two materials (HertzMindlin::Constants). The
// paper's Eqs. (5)-(7) are written for one material; a contact of two takes Hertz's and Mindlin's
// combined moduli (Johnson, Contact Mechanics, 1985, sections 4.2 and 7.2):
//   1/E* = (1 - nu_1)/(2 G_1) + (1 - nu_2)/(2 G_2)   (that is, (1 - nu^2)/E summed),
//   1/G* = (2 - nu_1)/G_1 + (2 - nu_2)/G_2,
// k_n = 2 E* a and k_s = 8 G* a at contact radius a, so k_s/k_n = 4 G*/E*, and Eq. (5)'s
// C_n = (3 E*^2)^(1/3) with C_s = (k_s/k_n) C_n. For one material these are the paper's constants
// (E* = G/(1 - nu), k_s/k_n = 2(1 - nu)/(2 - nu)), and the pair of equal materials returns
// HertzMindlin::constants itself, bit for bit. Friction: the smaller coefficient of the two.
#include <algorithm>
#include <cmath>

#include "contact/HertzMindlin.hpp"
#include "core/Material.hpp"

namespace trueaniso {

inline HertzMindlin::Constants pairConstants(const Material& a, const Material& b) {
  a.validate();
  b.validate();
  if (a.shearModulus == b.shearModulus && a.poisson == b.poisson) {
    HertzMindlin::Constants c = HertzMindlin::constants(a);
    c.mu = std::min(a.friction, b.friction);
    return c;
  }
  const Real Estar = 1.0 / ((1.0 - a.poisson) / (2.0 * a.shearModulus) + (1.0 - b.poisson) / (2.0 * b.shearModulus));
  const Real Gstar = 1.0 / ((2.0 - a.poisson) / a.shearModulus + (2.0 - b.poisson) / b.shearModulus);
  const Real ratio = 4.0 * Gstar / Estar;
  const Real Cn = std::cbrt(3.0 * Estar * Estar);
  return {ratio, std::min(a.friction, b.friction), Cn, ratio * Cn, 4.0 / 3.0 * Estar * std::sqrt(0.5),
          a.rollingStiffness, a.rollingFriction};
}

}  // namespace trueaniso
