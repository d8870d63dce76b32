// Stepper: detection against brute force, momentum conservation, Love-Weber stress of a simple
// cubic packing in closed form, YADE's unbalanced force, refusal of an unstable step.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "Drivers.hpp"
#include "contact/HertzMindlin.hpp"
#include "core/Parallel.hpp"
#include "RandomGas.hpp"
#include "dynamics/ContactRefresh.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"
#include "measure/Coordination.hpp"
#include "measure/ContactTerms.hpp"
#include "measure/Stress.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

std::shared_ptr<Scene> randomGas(int n, Real phi, unsigned seed, Real r = 1e-4) {
  return randomGasIn(Mat3::Identity(), n, phi, seed, r);
}

struct Chain {
  explicit Chain(std::shared_ptr<Scene> s, Real damping) : sim(s) {
    sim.add(detection = std::make_shared<ContactDetection>());
    sim.add(std::make_shared<ContactForces>());
    auto newton = std::make_shared<NewtonIntegrator>();
    newton->damping = damping;
    sim.add(newton);
  }
  Simulation sim;
  std::shared_ptr<ContactDetection> detection;
};

}  // namespace

// Every overlapping pair (minimum image, brute force O(n^2)) is listed and active, and nothing else
// is active. Exact comparison: both use the same distance formula on the same doubles.
TEST(ContactDetection, FindsExactlyTheOverlappingPairs) {
  auto s = randomGas(400, 0.55, 7);
  Driver drv(s);
  drv.evaluate();
  const Vec3 h = s->cell.hSize.diagonal();
  long brute = 0;
  for (int i = 0; i < s->bodies.size(); ++i)
    for (int j = i + 1; j < s->bodies.size(); ++j) {
      Vec3 d = s->bodies.pos[j] - s->bodies.pos[i];
      for (int k = 0; k < 3; ++k) d[k] -= h[k] * std::round(d[k] / h[k]);
      const Real rs = s->members.radius[i] + s->members.radius[j];
      if (d.squaredNorm() < rs * rs) ++brute;
    }
  long active = 0;
  for (int c = 0; c < s->contacts.size(); ++c) active += s->contacts.active(c);
  ASSERT_GT(brute, 100);
  EXPECT_EQ(active, brute);
  EXPECT_EQ(coordination(*s).contacts, brute);
}

// Each pair's image is indexed into the force loop's table of offsets (Contacts::image), in a
// sheared cell where an offset mixes the cell's columns, for spheres and for the dimers whose
// members stick out of the cell. The index names the pair's shift, and every contact's overlap is
// the one its shift gives through the cell's own product, hSize k (Cell::shiftVector), to 1e-12 of
// a radius: the same arithmetic but for the compiler's choice of fused multiply-adds (~1e-15 of
// the radius), where an offset with a column wrong would be off by a tenth of the cell.
TEST(ContactDetection, IndexesEachPairsImageForTheForceLoop) {
  for (int k = 0; k < Contacts::kImages; ++k) EXPECT_EQ(Contacts::imageIndex(Contacts::imageOf(k)), k);
  Mat3 shape;
  shape << 1, 0.3, -0.2, 0, 1.1, 0.25, 0, 0, 0.9;
  auto spheres = randomGasIn(shape, 400, 0.6, 3);
  auto dimers = randomDimers(300, 0.6, 9);
  dimers->cell.hSize = dimers->cell.hSize * shape;  // sheared, its reference kept
  for (auto& s : {spheres, dimers}) {
    refreshContacts(*s);
    const Contacts& C = s->contacts;
    const Members& M = s->members;
    int active = 0, mixed = 0;
    for (int c = 0; c < C.size(); ++c) {
      ASSERT_EQ(C.image[c], Contacts::imageIndex(C.shift[c])) << "pair " << c;
      if (!C.active(c)) continue;
      ++active;
      mixed += (C.shift[c].array() != 0).count() >= 2;
      const Vec3 d = M.pos[C.m2[c]] + s->cell.shiftVector(C.shift[c]) - M.pos[C.m1[c]];
      EXPECT_NEAR(C.overlap[c], M.radius[C.m1[c]] + M.radius[C.m2[c]] - d.norm(), 1e-12 * M.radius[C.m1[c]])
          << "contact " << c;
    }
    EXPECT_GT(active, 200);
    EXPECT_GT(mixed, 5);  // images across an edge of the cell, whose offsets mix two columns
  }
}

// A detection wraps the bodies that left the cell back into it and changes their pairs' image
// shifts; the branch vectors, read from the last force evaluation's centres (Contacts::branch),
// stay the vectors the forces were evaluated with. Half the bodies moved one cell vector out
// (their pairs' shifts changed to match: the same medium) and the forces evaluated there; the
// next detection wraps them back. Every active contact's L after the detection is its L before
// it, to the rounding of centres ~1e-3 m against a branch of ~2e-4 m (1e-14).
TEST(ContactDetection, WrappingKeepsTheBranchVectors) {
  auto s = randomGas(400, 0.55, 7);
  Driver drv(s);
  drv.evaluate();
  Contacts& C = s->contacts;
  const Vec3 a1 = s->cell.hSize.col(0);
  for (int b = 0; b < s->bodies.size(); b += 2) s->bodies.pos[b] += a1;
  for (int c = 0; c < C.size(); ++c) {
    C.shift[c].x() += (C.b1[c] % 2 == 0) - (C.b2[c] % 2 == 0);
    C.image[c] = Contacts::imageIndex(C.shift[c]);  // what the detection would write with it
  }
  s->refreshMembers();
  ContactForces().apply(*s);
  std::map<std::pair<int, int>, Vec3> before;  // active contacts by their spheres (one image each here)
  for (int c = 0; c < C.size(); ++c)
    if (C.active(c)) before[{C.m1[c], C.m2[c]}] = C.branch(c);
  s->detectionInvalid = true;
  ContactDetection().apply(*s);
  int active = 0, crossing = 0;
  for (int c = 0; c < C.size(); ++c) {
    if (!C.active(c)) continue;
    ++active;
    crossing += (C.b1[c] % 2) != (C.b2[c] % 2);
    const Vec3& L = before.at({C.m1[c], C.m2[c]});
    EXPECT_LE((C.branch(c) - L).norm(), 1e-14 * L.norm()) << "contact " << c;
  }
  EXPECT_EQ(active, static_cast<int>(before.size()));  // every contact kept, with its history
  EXPECT_GT(crossing, 100);  // pairs whose shift the wrap changed
}

// Closed periodic box, no damping: contact forces are pairwise opposite, so the total momentum
// is constant. Tolerance 1e-12 of sum |m v|: round-off of ~1e6 force additions. (The random gas
// starts with overlaps, so kinetic energy grows; momentum must not.)
TEST(NewtonIntegrator, ConservesMomentumWithoutDamping) {
  auto s = randomGas(300, 0.45, 11);
  std::mt19937_64 gen(3);
  std::normal_distribution<Real> Nd(0, 1);
  for (auto& v : s->bodies.vel) v = Vec3(Nd(gen), Nd(gen), Nd(gen)) * 0.05;
  Chain chain(s, 0.0);
  auto stepper = std::make_shared<TimeStepper>();
  stepper->maxDt = 1e-7;
  chain.sim.add(stepper);
  Driver(s).evaluate();
  stepper->apply(*s);
  auto momentum = [&] {
    Vec3 p = Vec3::Zero();
    Real scale = 0;
    for (int b = 0; b < s->bodies.size(); ++b) {
      p += s->bodies.mass[b] * s->bodies.vel[b];
      scale += s->bodies.mass[b] * s->bodies.vel[b].norm();
    }
    return std::make_pair(p, scale);
  };
  const auto [p0, scale] = momentum();
  chain.sim.run(3000);
  const Vec3 p1 = momentum().first;
  EXPECT_GT(chain.detection->rebuilds, 2);
  EXPECT_EQ(chain.detection->lostContacts, 0);
  EXPECT_LT((p1 - p0).norm(), 1e-12 * scale);
  EXPECT_TRUE(p1.allFinite());
}

// Simple cubic lattice, spacing a = 2r - delta: each sphere has one contact per axis direction, so
// sigma_kk = N l / a^3 = N / a^2 with N the Hertz force, and no shear stress.
TEST(Stress, SimpleCubicClosedForm) {
  const Real r = 1e-4, delta = 5e-7, a = 2 * r - delta;
  const int n = 4;
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  s->cell.setBox(Vec3::Constant(n * a));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) s->addSphere(Vec3(i + 0.5, j + 0.5, k + 0.5) * a, r);
  Driver(s).evaluate();
  const Real N = HertzMindlin(s->material).normalForce(delta, r);
  const Mat3 sigma = loveWeberStress(*s);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sigma(k, k) / (N / (a * a)), 1.0, 1e-12);
  EXPECT_NEAR((sigma - Mat3(sigma.diagonal().asDiagonal())).norm(), 0.0, 1e-12 * sigma.norm());
  const Coordination z = coordination(*s);
  EXPECT_EQ(z.contacts, 3 * n * n * n);
  EXPECT_DOUBLE_EQ(z.mechanical(), 6.0);
  EXPECT_NEAR(unbalancedForce(*s), 0.0, 1e-12);  // every sphere is balanced by symmetry
}

// YADE's definition on a configuration worked by hand: three spheres in a row, only the middle
// one balanced. Mean |F| over bodies = (N + 0 + N)/3, mean |contact force| = N.
TEST(Stress, UnbalancedForceFollowsYadeDefinition) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real r = 1e-4, delta = 1e-6;
  s->cell.setBox(Vec3::Constant(20 * r));
  s->addSphere(Vec3(5 * r, 10 * r, 10 * r), r);
  s->addSphere(Vec3(7 * r - delta, 10 * r, 10 * r), r);
  s->addSphere(Vec3(9 * r - 2 * delta, 10 * r, 10 * r), r);
  Driver(s).evaluate();
  EXPECT_NEAR(unbalancedForce(*s), 2.0 / 3.0, 1e-12);
  const Coordination z = coordination(*s);
  EXPECT_EQ(z.contacts, 2);
  EXPECT_EQ(z.oneContact, 2);
  EXPECT_EQ(z.noContact, 0);
  EXPECT_DOUBLE_EQ(z.mechanical(), (2.0 * 2 - 2) / (3 - 0 - 2));  // Eq. (14): 2
}

// The measures the cell controllers read, summed per block in lanes (measure/CellSums.hpp),
// against the plain sums over contacts and bodies in one running sum each (measure/ContactTerms.hpp),
// on a scene with shear forces and sliding: equal to round-off, 1e-12 of each quantity's size (the
// two orders of adding ~10,000 terms differ by a few hundred ulps at most). And the same bits with
// one thread and with a team (the pairs are enough for one: core/Parallel.hpp).
TEST(Stress, MeasuresAreTheirContactSumsAndIndependentOfThreads) {
  auto s = randomGasIn(Mat3::Identity(), 1500, 0.6, 5);
  s->dt = 1e-6;
  // Prescribed spins on every other sphere build tangential forces, some to the Coulomb cap.
  for (int b = 0; b < s->bodies.size(); b += 2) s->bodies.angVel[b] = Vec3(50, -30, 20);
  Driver driver(s);
  for (int k = 0; k < 3; ++k) { driver.evaluate(); driver.move(); }
  driver.evaluate();
  ASSERT_TRUE(worthThreads(s->contacts.size()));
  const Contacts& C = s->contacts;
  long sliding = 0, loaded = 0;
  Mat3 stress = Mat3::Zero();
  Vec6 stiffness = Vec6::Zero();
  Real contactForce = 0, bodyForce = 0;
  const Real ratio = HertzMindlin(s->material).shearToNormal();
  for (int c = 0; c < C.size(); ++c) {
    if (!C.active(c)) continue;
    ++loaded;
    sliding += C.shearForce[c].norm() >= 0.5 * (1 - 1e-12) * C.normalForce[c];
    addStressTerm(C.force(c), C.branch(c), stress);
    addAffineStiffnessTerm(HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]), ratio, C.normal[c],
                           C.branch(c), stiffness);
    contactForce += C.force(c).norm();
  }
  for (int b = 0; b < s->bodies.size(); ++b) bodyForce += s->bodies.force[b].norm();
  ASSERT_GT(sliding, 0);
  ASSERT_LT(sliding, loaded);
  const Real V = s->cell.volume();
  const Real unbalanced = (bodyForce / s->bodies.size()) / (contactForce / loaded);
  std::vector<ContactMeasures> byThreads;
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
#endif
    const ContactMeasures m = contactMeasures(*s);
    byThreads.push_back(m);
    EXPECT_LE((m.stress - stress / V).norm(), 1e-12 * m.stress.norm());
    EXPECT_LE((m.stiffness - stiffness / V).norm(), 1e-12 * m.stiffness.norm());
    EXPECT_NEAR(m.unbalanced, unbalanced, 1e-12 * unbalanced);
    EXPECT_EQ(m.stress, loveWeberStress(*s));
    EXPECT_EQ(m.stiffness, affineStiffness(*s));
    EXPECT_EQ(m.unbalanced, unbalancedForce(*s));
    EXPECT_GT(m.stress.trace(), 0.0);
#ifdef _OPENMP
  }
  omp_set_num_threads(saved);
#endif
  EXPECT_EQ(byThreads.front().stress, byThreads.back().stress);
  EXPECT_EQ(byThreads.front().stiffness, byThreads.back().stiffness);
  EXPECT_EQ(byThreads.front().unbalanced, byThreads.back().unbalanced);
}

// The time step's bounds, minima over the bodies, run on the team when the contact loop does
// (fewer bodies than worthThreads asks for, contacts enough): the same bits on one thread and two.
TEST(TimeStepper, BoundsOnATeamAreTheSerialOnes) {
  auto s = randomGasIn(Mat3::Identity(), 1500, 0.6, 5);
  s->dt = 1e-6;
  Driver driver(s);
  driver.evaluate();
  ASSERT_FALSE(worthThreads(s->bodies.size()));
  ASSERT_TRUE(worthThreadsBeside(s->bodies.size(), s->contacts.size()));
  std::vector<Real> perAxis, stiffness;
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
#endif
    perAxis.push_back(TimeStepper::perAxisBound(*s));
    stiffness.push_back(TimeStepper::stiffnessBound(*s));
#ifdef _OPENMP
  }
  omp_set_num_threads(saved);
#endif
  ASSERT_TRUE(std::isfinite(perAxis.front()) && perAxis.front() > 0);
  EXPECT_EQ(perAxis.front(), perAxis.back());
  EXPECT_EQ(stiffness.front(), stiffness.back());
}

// A step above the two-body limit of the stiffest contact is refused before it is taken.
TEST(NewtonIntegrator, RefusesUnstableStep) {
  auto s = twoSpheres(1e-4, 1e-4, 1e-6);
  Chain chain(s, 0.0);
  Driver(s).evaluate();
  const Real limit = TimeStepper::criticalPairStep(*s);
  s->dt = 1.01 * limit;
  const Vec3 before = s->bodies.pos[1];
  EXPECT_THROW(chain.sim.run(1), InputError);
  EXPECT_EQ(s->bodies.pos[1], before);  // nothing moved
  s->dt = 0.5 * limit;
  EXPECT_NO_THROW(chain.sim.run(10));
  // Raised within the check interval, past the limit: refused at the next step, not at the interval's end.
  s->dt = 1.01 * TimeStepper::criticalPairStep(*s);
  const Vec3 now = s->bodies.pos[1];
  EXPECT_THROW(chain.sim.run(1), InputError);
  EXPECT_EQ(s->bodies.pos[1], now);
}

// The time stepper's choice is stable: an undamped, loaded random packing keeps its energy
// bounded over many steps (an unstable step grows it exponentially within tens of steps).
TEST(TimeStepper, ChosenStepIsStable) {
  auto s = randomGas(300, 0.62, 5);
  Chain chain(s, 0.0);
  auto stepper = std::make_shared<TimeStepper>();
  stepper->maxDt = 1.0;  // no cap: the contacts alone decide
  chain.sim.add(stepper);
  Driver(s).evaluate();
  stepper->apply(*s);
  auto energy = [&] {
    Real e = 0;
    for (int b = 0; b < s->bodies.size(); ++b) e += 0.5 * s->bodies.mass[b] * s->bodies.vel[b].squaredNorm();
    for (int c = 0; c < s->contacts.size(); ++c)
      if (s->contacts.active(c)) e += 0.4 * s->contacts.normalForce[c] * s->contacts.overlap[c];
    return e;
  };
  chain.sim.run(50);
  const Real e0 = energy();
  chain.sim.run(3000);
  EXPECT_LT(energy(), 1.5 * e0);
}

TEST(Scene, RejectsBadInput) {
  Scene s;
  EXPECT_THROW(s.addSphere(Vec3::Zero(), 0.0), InputError);
  EXPECT_THROW(s.addSphere(Vec3::Zero(), -1.0), InputError);
  EXPECT_THROW(s.validate(), InputError);  // empty
  s.cell.setBox(Vec3::Constant(1e-4));
  s.addSphere(Vec3::Zero(), 1e-4);
  EXPECT_THROW(s.validate(), InputError);  // solid volume exceeds the cell
}

// The force reduction sums only the buffers of threads that ran this step. A team smaller than
// omp_get_max_threads() (here: the loop called from inside an active parallel region, where the
// nested region gets one thread) once added the stale buffer of a thread absent this step.
// Exact comparison: one thread sums the contacts in the same order either way.
TEST(ContactForces, SumsOnlyTheThreadsThatRan) {
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  auto s = randomGas(1500, 0.6, 11);
  s->dt = 1e-8;
  ContactDetection detection;
  detection.rebuild(*s);
  s->detectionInvalid = false;
  ContactForces forces;
  // Enough pairs for a team (core/Parallel.hpp): thread 1's buffer then holds this step's share.
  ASSERT_TRUE(worthThreads(s->contacts.size()));
  forces.apply(*s);
  for (Vec3& p : s->bodies.pos) p *= 1.0 + 1e-4;  // other forces next time
  s->cell.hSize *= 1.0 + 1e-4;
  s->members.pos = s->bodies.pos;
  ContactForces serial;
  Scene reference = *s;
  omp_set_num_threads(1);
  serial.apply(reference);
  omp_set_num_threads(2);
  // Inside an active region with one active level allowed, the loop's own region gets a team of
  // one, while omp_get_max_threads() still says 2.
  const int levels = omp_get_max_active_levels();
  omp_set_max_active_levels(1);
  int inner = 0;
#pragma omp parallel num_threads(2)
#pragma omp single
  {
    inner = omp_get_max_threads();
    forces.apply(*s);
  }
  omp_set_max_active_levels(levels);
  omp_set_num_threads(saved);
  ASSERT_EQ(inner, 2);
  Real worst = 0, scale = 0;
  for (int b = 0; b < s->bodies.size(); ++b) {
    worst = std::max(worst, (s->bodies.force[b] - reference.bodies.force[b]).norm());
    scale = std::max(scale, reference.bodies.force[b].norm());
  }
  EXPECT_EQ(worst, 0.0) << "relative to the largest force " << scale;
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

// Every touching pair's force and moments reach both bodies, whatever batch of the force loop it
// falls in (ContactForces walks pairs in batches, the last one partial): each body's force and
// torque equal the pair-order sums of the contact forces the loop stored, to the bit on one
// thread; with a team of two, within round-off of the two buffers' sum.
TEST(ContactForces, BodiesReceiveEveryPairInOrder) {
  auto s = randomGas(1500, 0.6, 13);
  s->dt = 1e-6;
  for (int b = 0; b < s->bodies.size(); b += 3) s->bodies.angVel[b] = Vec3(-40, 25, 60);  // shear forces
  Driver driver(s);
  driver.evaluate();
  driver.move();
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
#else
  for (int threads : {1}) {
#endif
    driver.evaluate();
    const Contacts& C = s->contacts;
    ASSERT_NE(C.size() % 32, 0) << "choose a scene whose last batch is partial";
    std::vector<Vec3> F(s->bodies.size(), Vec3::Zero()), T(s->bodies.size(), Vec3::Zero());
    int touching = 0;
    for (int c = 0; c < C.size(); ++c) {
      if (!C.active(c)) continue;
      ++touching;
      const Vec3 Fc = C.force(c), n = C.normal[c];
      const int a = C.b1[c], b = C.b2[c];
      const Real ra = s->members.radius[C.m1[c]], rb = s->members.radius[C.m2[c]];
      F[a] -= Fc;
      F[b] += Fc;
      T[a] -= Vec3((ra - 0.5 * C.overlap[c]) * n).cross(Fc);
      T[b] += Vec3(-(rb - 0.5 * C.overlap[c]) * n).cross(Fc);
    }
    ASSERT_GT(touching, 1000);
    Real scale = 0, worstF = 0, worstT = 0, torqueScale = 0;
    for (int b = 0; b < s->bodies.size(); ++b) {
      scale = std::max(scale, F[b].norm());
      torqueScale = std::max(torqueScale, T[b].norm());
      worstF = std::max(worstF, (s->bodies.force[b] - F[b]).norm());
      worstT = std::max(worstT, (s->bodies.torque[b] - T[b]).norm());
    }
    ASSERT_GT(torqueScale, 0.0);
    // One thread adds in pair order, as here: exact. Two: each body's sum split in two parts,
    // a few ulps of the largest force (1e-13 relative allows ~500).
    const Real tol = threads == 1 ? 0.0 : 1e-13;
    EXPECT_LE(worstF, tol * scale) << threads << " threads";
    EXPECT_LE(worstT, tol * torqueScale) << threads << " threads";
  }
#ifdef _OPENMP
  omp_set_num_threads(saved);
#endif
}

// A step of a small scene runs on the calling thread whatever the thread count (core/Parallel.hpp):
// two threads on 300 spheres took 8-13 ms a step against 0.22 ms with another process on the
// second core. Observable as bit-identical forces with one and two threads (a team sums the
// threads' buffers in another order than one thread sums the contacts).
TEST(ContactForces, SmallScenesStayOnOneThread) {
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  auto s = randomGas(300, 0.6, 11);
  s->dt = 1e-8;
  ContactDetection detection;
  detection.rebuild(*s);
  s->detectionInvalid = false;
  ASSERT_EQ(parallelMinimum(), kDefaultParallelMinimum);
  ASSERT_FALSE(worthThreads(s->contacts.size()));
  Scene two = *s;
  omp_set_num_threads(1);
  ContactForces().apply(*s);
  omp_set_num_threads(2);
  ContactForces().apply(two);
  omp_set_num_threads(saved);
  for (int b = 0; b < s->bodies.size(); ++b) ASSERT_EQ(s->bodies.force[b], two.bodies.force[b]) << "body " << b;
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

// The integrator and the detection run on the team when the step's contact loop does, even with
// fewer bodies than parallelMinimum() (core/Parallel.hpp, worthThreadsBeside), and give the same
// bits as on one thread: each body is integrated on its own, the displacement check takes a
// maximum, the pairs found are joined in index order. A sheared cell with a velocity gradient, so
// that the affine map and the sheared check run too.
TEST(NewtonIntegrator, AndTheDetectionGiveTheSameBitsOnATeam) {
#ifdef _OPENMP
  const int saved = omp_get_max_threads();
  Mat3 shape = Mat3::Identity();
  shape(0, 1) = 0.05;
  auto s = randomGasIn(shape, 1500, 0.62, 9);
  for (int b = 0; b < s->bodies.size(); b += 2) s->bodies.angVel[b] = Vec3(50, -30, 20);
  s->cell.velGrad(0, 2) = 2.0;
  s->cell.velGrad(1, 1) = -1.0;
  ContactDetection first;
  first.rebuild(*s);
  s->detectionInvalid = false;
  ContactForces().apply(*s);
  s->dt = 0.2 * TimeStepper::stiffnessBound(*s);
  ASSERT_FALSE(worthThreads(s->bodies.size()));
  ASSERT_TRUE(worthThreadsBeside(s->bodies.size(), s->contacts.size()));
  std::vector<Scene> byThreads;
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    Scene t = *s;
    NewtonIntegrator newton;
    newton.damping = 0.2;
    for (int k = 0; k < 5; ++k) newton.apply(t);  // the same forces every step: the integrator alone
    ContactDetection detection = first;
    EXPECT_TRUE(detection.needsRebuild(t) == first.needsRebuild(t));
    detection.rebuild(t);
    byThreads.push_back(t);
  }
  omp_set_num_threads(saved);
  const Scene &a = byThreads[0], &b = byThreads[1];
  for (int k = 0; k < a.bodies.size(); ++k) {
    ASSERT_EQ(a.bodies.pos[k], b.bodies.pos[k]) << "body " << k;
    ASSERT_EQ(a.bodies.vel[k], b.bodies.vel[k]) << "body " << k;
    ASSERT_EQ(a.bodies.angVel[k], b.bodies.angVel[k]) << "body " << k;
  }
  ASSERT_EQ(a.cell.hSize, b.cell.hSize);
  ASSERT_EQ(a.contacts.size(), b.contacts.size());
  for (int c = 0; c < a.contacts.size(); ++c) {
    ASSERT_EQ(a.contacts.m1[c], b.contacts.m1[c]) << "pair " << c;
    ASSERT_EQ(a.contacts.m2[c], b.contacts.m2[c]) << "pair " << c;
    ASSERT_EQ(a.contacts.shift[c], b.contacts.shift[c]) << "pair " << c;
  }
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

// A contact refresh at unchanged positions gives back every tangential force bit for bit, however
// often it runs (each refresh once shifted them by ~3e-19 N, and the shift accumulated).
TEST(ContactRefresh, IsExactAtTheSamePositions) {
  auto s = randomGas(300, 0.62, 5);
  s->dt = 1e-8;
  Chain chain(s, 0.2);
  for (int k = 0; k < 50; ++k) {
    s->cell.velGrad = Vec3(-1.0, -2.0, -3.0).asDiagonal();
    chain.sim.run(1);  // sheared contacts: tangential forces with history
  }
  refreshContacts(*s);
  const Scene first = *s;
  long loaded = 0;
  for (int c = 0; c < first.contacts.size(); ++c) loaded += first.contacts.shearForce[c].norm() > 0;
  ASSERT_GT(loaded, 100);
  for (int k = 0; k < 100; ++k) refreshContacts(*s);
  ASSERT_EQ(s->contacts.size(), first.contacts.size());
  for (int c = 0; c < s->contacts.size(); ++c) {
    EXPECT_EQ(s->contacts.shearForce[c], first.contacts.shearForce[c]);
    EXPECT_EQ(s->contacts.normalForce[c], first.contacts.normalForce[c]);
  }
  EXPECT_EQ(s->dt, 1e-8);  // the zero-time evaluation leaves the scene's step alone
}

// A pair whose image lies farther than the force loop's table reaches (Contacts::kImageReach
// cells on an axis) is refused with what to change: here rods of seven balls, 10 radii long, in a
// cell 2.5 radii wide along them, whose members stick out of it by up to four cell widths.
TEST(ContactDetection, RefusesAPairFartherThanTheImageTableReaches) {
  const Real r = 1e-4;
  std::vector<Vec3> at;
  for (int k = 0; k < 7; ++k) at.push_back(Vec3(1.5 * k * r, 0, 0));
  const ClumpTemplate rod = makeClumpTemplate(at, std::vector<Real>(7, r));
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  s->cell.setBox(Vec3(2.5 * r, 20 * r, 20 * r));
  s->addClump(Vec3(0.1 * r, 0.2 * r, 0.3 * r), Quat::Identity(), rod);
  s->addClump(Vec3(1.3 * r, 1.2 * r, 1.1 * r), Quat::Identity(), rod);
  try {
    refreshContacts(*s);
    FAIL() << "a pair across more than two cells was not refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the cell is too small for these particles"), std::string::npos) << e.what();
  }
}
