// The gap-tolerant contact count Zm_gap (measure/Coordination.hpp): a slightly expanded
// simple cubic lattice in closed form, and a brute-force count on a random packing.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "Drivers.hpp"
#include "Lattices.hpp"
#include "dynamics/ContactRefresh.hpp"
#include "measure/Coordination.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

// Every neighbour pair of a simple cubic lattice expanded to a gap of 5e-4 d: no contact (Zm of
// Eq. 14 is undefined, NaN: no particle has 2 contacts), but with the default tolerance 1e-3 d
// every sphere has its 6 neighbours (Zm_gap = 6 exactly); a tolerance of 4e-4 d counts none.
TEST(CoordinationGap, ExpandedSimpleCubicLattice) {
  const Real gap = 5e-4 * 2 * kR;
  auto s = simpleCubic(4, Vec3::Constant(-gap));
  refreshContacts(*s);
  const Coordination z = coordination(*s);
  EXPECT_EQ(z.contacts, 0);
  EXPECT_TRUE(std::isnan(z.mechanical()));
  const Coordination g = coordinationWithinGap(*s);  // kGapTolerance = 1e-3
  EXPECT_EQ(g.contacts, 3 * 64);
  EXPECT_EQ(g.noContact + g.oneContact, 0);
  EXPECT_EQ(g.mechanical(), 6.0);
  const Coordination tight = coordinationWithinGap(*s, 4e-4);
  EXPECT_EQ(tight.contacts, 0);
  // Tolerance 0: the touching pairs only, as coordination() counts them.
  auto t = simpleCubic(4, Vec3::Constant(1e-6));
  refreshContacts(*t);
  EXPECT_EQ(coordinationWithinGap(*t, 0.0).mechanical(), 6.0);
  EXPECT_EQ(coordinationWithinGap(*t, 0.0).contacts, coordination(*t).contacts);
}

// A random polydisperse packing (overlaps and near-misses of all sizes): the counts per body
// equal a brute-force O(n^2) minimum-image count of pairs with centre distance below
// (1 + tol)(r1 + r2), for tolerances from 0 to 0.04 (the largest the Verlet skin allows, 0.05).
// Exact: both read the same doubles; a pair within round-off of the threshold is improbable.
TEST(CoordinationGap, MatchesBruteForceOnRandomPacking) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<Real> U(0, 1);
  const int n = 500;
  std::vector<Real> radii(n);
  Real vol = 0;
  for (Real& x : radii) { x = kR * (0.7 + 0.6 * U(gen)); vol += 4.0 / 3.0 * M_PI * x * x * x; }
  const Real side = std::cbrt(vol / 0.6);
  s->cell.setBox(Vec3::Constant(side));
  for (int i = 0; i < n; ++i) s->addSphere(Vec3(U(gen), U(gen), U(gen)) * side, radii[i]);
  refreshContacts(*s);
  for (Real tol : {0.0, 1e-3, 1e-2, 0.04}) {
    std::vector<int> brute(n, 0);
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) {
        Vec3 d = s->bodies.pos[j] - s->bodies.pos[i];
        for (int k = 0; k < 3; ++k) d[k] -= side * std::round(d[k] / side);
        const Real rs = radii[i] + radii[j];
        if (rs - d.norm() > -tol * rs) { ++brute[i]; ++brute[j]; }
      }
    const std::vector<int> count = contactsPerBodyWithinGap(*s, tol);
    long more = 0;
    for (int b = 0; b < n; ++b) more += brute[b];
    EXPECT_EQ(count, brute) << "tol " << tol;
    // A random gas has few gaps below 1e-3 d; the larger tolerances must find near-misses.
    if (tol >= 1e-2) EXPECT_GT(more / 2, coordination(*s).contacts) << "tol " << tol << " adds no pair";
  }
}

// Bad tolerances are refused before any counting: negative, NaN, or beyond what the skin holds.
TEST(CoordinationGap, RefusesBadTolerance) {
  auto s = simpleCubic(3, Vec3::Constant(1e-6));
  refreshContacts(*s);
  EXPECT_THROW(coordinationWithinGap(*s, -1e-3), InputError);
  EXPECT_THROW(coordinationWithinGap(*s, std::nan("")), InputError);
  EXPECT_THROW(coordinationWithinGap(*s, 0.05), InputError);
  EXPECT_NO_THROW(coordinationWithinGap(*s, 0.049));
}

// Eq. (14) can fall when near-contacts are counted: a particle with one contact (excluded, only
// its contact's other end counted) that gains a second enters the mechanical set with 2 contacts,
// below a mean near 6. Counts of 100 particles, 290 contacts, 4 with one contact: Zm = 576/96 =
// 6.0; one of the four gains a near-contact: (582 - 3)/97 = 5.969, lower.
TEST(CoordinationGap, ParticleJoiningWithTwoContactsLowersZm) {
  Coordination touching;
  touching.particles = 100;
  touching.contacts = 290;
  touching.oneContact = 4;
  Coordination withGap = touching;
  withGap.contacts = 291;
  withGap.oneContact = 3;
  EXPECT_DOUBLE_EQ(touching.mechanical(), 6.0);
  EXPECT_DOUBLE_EQ(withGap.mechanical(), 579.0 / 97.0);
  EXPECT_LT(withGap.mechanical(), touching.mechanical());
}
