// Bodies renumbered along a Morton curve (core/SpaceOrder): the code interleaves the axes, the
// renumbering brings contacting bodies near in memory, and a renumbered scene (spheres and clumps,
// with contact history) steps as the original does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <tuple>

#include "FabricScenes.hpp"
#include "RandomGas.hpp"
#include "core/SpaceOrder.hpp"
#include "dynamics/ContactDetection.hpp"
#include "dynamics/ContactForces.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

// The median distance in memory (body indices) of the two bodies of a contact.
int medianIndexDistance(const Scene& s) {
  const Contacts& C = s.contacts;
  std::vector<int> d;
  for (int c = 0; c < C.size(); ++c)
    if (C.active(c)) d.push_back(std::abs(C.b2[c] - C.b1[c]));
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

// Steps a scene and a renumbered copy side by side and compares them body by body.
void expectSameDynamics(std::shared_ptr<Scene> s) {
  ContactDetection().apply(*s);
  ContactForces().apply(*s);  // the overlaps that set the stable step
  s->dt = 0.3 * TimeStepper::criticalPairStep(*s);
  Simulation a = steppingChain(s, 0.2);
  a.run(300);  // contacts with shear history
  auto t = std::make_shared<Scene>(*s);
  const std::vector<int> order = spaceOrder(*t);
  int moved = 0;
  for (int k = 0; k < static_cast<int>(order.size()); ++k) moved += order[k] != k;
  ASSERT_GT(moved, static_cast<int>(order.size()) / 2);  // a real renumbering, not the identity
  reorderBodies(*t, order);

  // Every contact is there with its history, seen from the same or the other side.
  const Contacts &C = s->contacts, &D = t->contacts;
  ASSERT_EQ(C.size(), D.size());
  std::vector<int> newBody(order.size());
  for (size_t k = 0; k < order.size(); ++k) newBody[order[k]] = static_cast<int>(k);
  std::map<std::tuple<int, int, int, int, int>, int> index;
  for (int c = 0; c < D.size(); ++c) index[{D.m1[c], D.m2[c], D.shift[c][0], D.shift[c][1], D.shift[c][2]}] = c;
  for (int c = 1; c < D.size(); ++c)  // sorted as the detection keeps them
    ASSERT_TRUE(std::tie(D.m1[c - 1], D.m2[c - 1]) <= std::tie(D.m1[c], D.m2[c]));
  int active = 0;
  for (int c = 0; c < C.size(); ++c) {
    if (!C.active(c)) continue;
    ++active;
    // Members of a body stay contiguous in body order: find the pair by its bodies and force.
    const int b1 = newBody[C.b1[c]], b2 = newBody[C.b2[c]];
    bool found = false;
    for (int d = 0; d < D.size() && !found; ++d) {
      if (D.normalForce[d] != C.normalForce[c]) continue;
      const bool same = D.b1[d] == b1 && D.b2[d] == b2, swapped = D.b1[d] == b2 && D.b2[d] == b1;
      // The branch vector follows its bodies (Contacts::branch): the same bits seen from the same
      // side; from the other side the opposite vector to the rounding of the centres it is
      // computed from (centres up to tens of radii from the origin: tens of ulps of a branch of ~2 radii).
      const Vec3 L = C.branch(c);
      if (same)
        found = D.shearForce[d] == C.shearForce[c] && D.normal[d] == C.normal[c] &&
                D.rollingMoment[d] == C.rollingMoment[c] && D.branch(d) == L;
      if (swapped)
        found = D.shearForce[d] == -C.shearForce[c] && D.normal[d] == -C.normal[c] &&
                D.rollingMoment[d] == -C.rollingMoment[c] && (D.branch(d) + L).norm() <= 1e-13 * L.norm();
    }
    ASSERT_TRUE(found) << "contact " << c << " lost its history in the renumbering";
  }
  ASSERT_GT(active, 100);
  ASSERT_EQ(t->contacts.incBegin.size(), order.size() + 1);

  // Both step on; only the summation order of forces differs (round-off, ~1e-16 relative per
  // step, grown by the packing's instability over 300 steps): positions agree to 1e-9 of a radius.
  Simulation b = steppingChain(t, 0.2);
  a.run(300);
  b.run(300);
  const Real r = s->maxRadius();
  Real worst = 0;
  for (size_t k = 0; k < order.size(); ++k) {
    // Positions are compared modulo the cell: the renumbered scene's detection rebuilt (and
    // wrapped its bodies into the cell) at other steps than the original's.
    const Vec3 d = t->bodies.pos[k] - s->bodies.pos[order[k]];
    const Vec3 image = (s->cell.hSize.inverse() * d).array().round().matrix();
    worst = std::max(worst, (d - s->cell.hSize * image).norm());
    if (s->hasClumps())
      worst = std::max(worst, r * (t->bodies.orientation[k].coeffs() - s->bodies.orientation[order[k]].coeffs()).norm());
  }
  EXPECT_LT(worst, 1e-9 * r);
}

}  // namespace

TEST(SpaceOrder, MortonCodeInterleavesTheAxes) {
  const Real slice = 1.0 / 1024;
  EXPECT_EQ(mortonCode(Vec3(0, 0, 0)), 0u);
  EXPECT_EQ(mortonCode(Vec3(1.5 * slice, 0, 0)), 1u);
  EXPECT_EQ(mortonCode(Vec3(0, 1.5 * slice, 0)), 2u);
  EXPECT_EQ(mortonCode(Vec3(0, 0, 1.5 * slice)), 4u);
  EXPECT_EQ(mortonCode(Vec3(3.5 * slice, 0, 0)), 9u);                // x = 0b11 -> bits 0 and 3
  EXPECT_EQ(mortonCode(Vec3(1.0 + 1.5 * slice, -1.0, 0)), 1u);       // wrapped into the cell
  EXPECT_EQ(mortonCode(Vec3(1.0 - 0.5 * slice, 1.0 - 0.5 * slice, 1.0 - 0.5 * slice)), (1u << 30) - 1);
}

// In a random gas numbered in generation order, contacting bodies are about n/3 apart in memory;
// along the curve (2000 spheres) the median distance falls below a tenth of that (measured: see the
// assertion message; the mean stays larger, from the curve's long jumps and the periodic seams).
TEST(SpaceOrder, ContactingBodiesBecomeNearInMemory) {
  auto s = randomGasIn(Mat3::Identity(), 2000, 0.6, 3);
  ContactDetection detection;
  detection.apply(*s);
  ContactForces().apply(*s);
  const int before = medianIndexDistance(*s);
  reorderBodies(*s, spaceOrder(*s));
  detection.apply(*s);
  ContactForces().apply(*s);
  const int after = medianIndexDistance(*s);
  EXPECT_GT(before, 400);
  EXPECT_LT(after, 0.1 * before) << "median |b2 - b1| " << before << " -> " << after;
}

TEST(SpaceOrder, RenumberedSpheresStepAsTheOriginal) { expectSameDynamics(randomGasIn(Mat3::Identity(), 400, 0.62, 5)); }

// With rolling resistance (docs/rolling.md) the rolling moments are history too.
TEST(SpaceOrder, RenumberedSpheresWithRollingResistanceStepAsTheOriginal) {
  auto s = randomGasIn(Mat3::Identity(), 400, 0.62, 5);
  s->material.rollingStiffness = 0.25;
  s->material.rollingFriction = 0.1;
  expectSameDynamics(s);
  Real largest = 0;
  for (const Vec3& m : s->contacts.rollingMoment) largest = std::max(largest, m.norm());
  EXPECT_GT(largest, 0.0);  // the premise: moments were carried
}

TEST(SpaceOrder, RenumberedClumpsStepAsTheOriginal) { expectSameDynamics(randomGas(300, 0.6, 9, true)); }

TEST(SpaceOrder, RefusesAnOrderThatIsNotAPermutation) {
  auto s = randomGasIn(Mat3::Identity(), 10, 0.3, 1);
  EXPECT_THROW(reorderBodies(*s, {0, 1, 2}), InputError);
  EXPECT_THROW(reorderBodies(*s, {0, 0, 2, 3, 4, 5, 6, 7, 8, 9}), InputError);
}
