// The contact law's constants for two materials (contact/MaterialPair.hpp) against an independent
// derivation: the contact of two elastic half-spaces as two springs in series, each half-space
// pressed by the contact disc of radius a. A half-space of Young's modulus E_i and Poisson ratio
// nu_i under a rigid disc has normal stiffness 2 a E_i/(1 - nu_i^2) (Boussinesq) and tangential
// stiffness 8 a G_i/(2 - nu_i) (Mindlin's no-slip disc), and Hertz gives a = sqrt(R* delta).
#include <gtest/gtest.h>

#include <cmath>

#include "contact/HertzMindlin.hpp"
#include "contact/MaterialPair.hpp"

using namespace trueaniso;

namespace {
Material material(Real G, Real nu, Real mu = 0.5) {
  Material m;
  m.shearModulus = G;
  m.poisson = nu;
  m.friction = mu;
  return m;
}
}  // namespace

TEST(MaterialPair, OneMaterialIsThePapersConstantsBitForBit) {
  const Material m = material(18e9, 0.15);
  const HertzMindlin::Constants a = HertzMindlin::constants(m), b = pairConstants(m, m);
  EXPECT_EQ(a.ratio, b.ratio);
  EXPECT_EQ(a.Cn, b.Cn);
  EXPECT_EQ(a.Cs, b.Cs);
  EXPECT_EQ(a.hertzUnit, b.hertzUnit);
  EXPECT_EQ(a.mu, b.mu);
}

TEST(MaterialPair, TwoMaterialsAreHalfSpacesInSeries) {
  const Real G1 = 18e9, nu1 = 0.15, G2 = 70e9, nu2 = 0.3;
  const Material m1 = material(G1, nu1, 0.5), m2 = material(G2, nu2, 0.3);
  const HertzMindlin::Constants c = pairConstants(m1, m2);
  const HertzMindlin law(c);
  const Real r1 = 0.1e-3, r2 = 0.2e-3, delta = 2e-7;
  const Real rbar = 2 * r1 * r2 / (r1 + r2), Rstar = rbar / 2, a = std::sqrt(Rstar * delta);
  const Real E1 = 2 * G1 * (1 + nu1), E2 = 2 * G2 * (1 + nu2);
  const Real kn1 = 2 * a * E1 / (1 - nu1 * nu1), kn2 = 2 * a * E2 / (1 - nu2 * nu2);
  const Real ks1 = 8 * a * G1 / (2 - nu1), ks2 = 8 * a * G2 / (2 - nu2);
  const Real kn = 1 / (1 / kn1 + 1 / kn2), ks = 1 / (1 / ks1 + 1 / ks2);
  // Hertz: N = (2/3) k_n delta for the force whose tangent is k_n at this overlap.
  const Real N = law.normalForce(delta, rbar);
  // Round-off of a few operations on each side: 1e-13.
  EXPECT_NEAR(N, 2.0 / 3.0 * kn * delta, 1e-13 * N);
  EXPECT_NEAR(HertzMindlin::normalStiffness(N, delta), kn, 1e-13 * kn);
  EXPECT_NEAR(law.shearStiffness(HertzMindlin::normalStiffness(N, delta)), ks, 1e-13 * ks);
  // Eqs. (5)-(6) written with the pair's C_n, C_s give the same stiffnesses from the force.
  EXPECT_NEAR(law.knFromForce(N, rbar), kn, 1e-13 * kn);
  EXPECT_NEAR(law.ksFromForce(N, rbar), ks, 1e-13 * ks);
  EXPECT_EQ(c.mu, 0.3);  // the smaller friction
  // Symmetric in the two materials (to round-off: the sums' order changes).
  const HertzMindlin::Constants d = pairConstants(m2, m1);
  EXPECT_NEAR(d.hertzUnit, c.hertzUnit, 1e-15 * c.hertzUnit);
  EXPECT_NEAR(d.ratio, c.ratio, 1e-15 * c.ratio);
}

TEST(MaterialPair, RefusesAMaterialOutOfRange) {
  EXPECT_THROW(pairConstants(material(18e9, 0.15), material(18e9, 0.5)), InputError);
  EXPECT_THROW(pairConstants(material(-1, 0.15), material(18e9, 0.15)), InputError);
  EXPECT_THROW(pairConstants(material(std::nan(""), 0.15), material(18e9, 0.15)), InputError);
}
