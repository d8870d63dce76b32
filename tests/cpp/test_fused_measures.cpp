// The cell measures the contact loop sums while it computes the forces (measure/CellSums.hpp)
// against the separate pass over the contacts and bodies (contactMeasures): the Love-Weber stress,
// the affine stiffness and the unbalanced force, on packings of spheres and of clumps, with one
// thread and with a team of two. Equal bits on the baseline build (the same terms added in the
// same blocks and order); the last digits on a build for x86-64-v3, where the compiler fuses
// multiply-adds where it chooses (SameBits.hpp).
#include <gtest/gtest.h>

#include <limits>
#include <random>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "Drivers.hpp"
#include "RandomGas.hpp"
#include "SameBits.hpp"
#include "clump/ClumpTemplate.hpp"
#include "contact/HertzMindlin.hpp"
#include "control/TrueTriaxialServo.hpp"
#include "core/Parallel.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"
#include "measure/CellLanes.hpp"
#include "measure/CellSums.hpp"
#include "measure/ContactTerms.hpp"
#include "measure/Reduce.hpp"
#include "measure/Stress.hpp"

// Vectors of four lanes (measure/CellLanes.hpp) are passed only to functions that are always
// inlined: GCC's note that such a call would change the ABI on the baseline does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

// A step well inside the stability limit of the scene's overlaps as placed.
void stableStep(Scene& s) {
  ContactDetection detection;
  detection.apply(s);
  ContactForces().apply(s);
  s.dt = 0.2 * TimeStepper::stiffnessBound(s);
}

// Spheres at a solid fraction where they overlap, spun so that tangential forces build up (some
// to the Coulomb cap).
std::shared_ptr<Scene> spheres() {
  auto s = randomGasIn(Mat3::Identity(), 3000, 0.62, 11);
  for (int b = 0; b < s->bodies.size(); b += 2) s->bodies.angVel[b] = Vec3(50, -30, 20);
  stableStep(*s);
  return s;
}

// Asymmetric dimers at random orientations, spun likewise: the branch vectors join clump centres,
// not the touching members.
std::shared_ptr<Scene> clumps() {
  auto s = randomDimers(2000, 0.6, 3);
  for (int b = 0; b < s->bodies.size(); b += 2) s->bodies.angVel[b] = Vec3(40, 20, -35);
  stableStep(*s);
  return s;
}

// Reads the cell measures as a controller does, every step, and keeps how far the force loop's
// sums were from the separate pass (relative to each quantity's size) and whether it had them.
class Reader : public Engine {
 public:
  void apply(Scene& s) override {
    fused = fused && s.measured.current(s.step);
    const ContactMeasures a = cellMeasures(s), b = contactMeasures(s);
    stress = std::max(stress, (a.stress - b.stress).norm() / b.stress.norm());
    stiffness = std::max(stiffness, (a.stiffness - b.stiffness).norm() / b.stiffness.norm());
    unbalanced = std::max(unbalanced, std::abs(a.unbalanced - b.unbalanced) / b.unbalanced);
    ++reads;
  }
  std::string name() const override { return "Reader"; }
  bool readsCellMeasures() const override { return true; }
  bool fused = true;
  Real stress = 0, stiffness = 0, unbalanced = 0;
  long reads = 0;
};

// Runs another engine but does not say that it reads the measures: its steps sum nothing in the
// force loop, and the measures it reads come from the separate pass.
class Unannounced : public Engine {
 public:
  explicit Unannounced(std::shared_ptr<Engine> e) : inner(std::move(e)) {}
  void apply(Scene& s) override { inner->apply(s); done = inner->done; }
  std::string name() const override { return inner->name(); }
  std::shared_ptr<Engine> inner;
};

Simulation chain(std::shared_ptr<Scene> s, const std::vector<std::shared_ptr<Engine>>& controllers) {
  Simulation sim(std::move(s));
  sim.add(std::make_shared<ContactDetection>());
  sim.add(std::make_shared<ContactForces>());
  for (const auto& e : controllers) sim.add(e);
  auto newton = std::make_shared<NewtonIntegrator>();
  newton->damping = 0.2;
  sim.add(newton);
  return sim;
}

struct Threads {  // the OpenMP thread count for the scope of the object
  explicit Threads(int n) {
#ifdef _OPENMP
    saved = omp_get_max_threads();
    omp_set_num_threads(n);
#endif
  }
  ~Threads() {
#ifdef _OPENMP
    omp_set_num_threads(saved);
#endif
  }
  int saved = 1;
};

class FusedMeasures : public ::testing::TestWithParam<std::tuple<bool, int>> {
 protected:
  std::shared_ptr<Scene> scene() const { return std::get<0>(GetParam()) ? clumps() : spheres(); }
  int threads() const { return std::get<1>(GetParam()); }
};

}  // namespace

// Every step of a run with an engine that reads them: the force loop's sums are there, and they
// are the separate pass's. The scene is big enough for the force loop's team (core/Parallel.hpp),
// with several blocks of pairs and of bodies per thread.
TEST_P(FusedMeasures, EqualTheSeparatePassEveryStep) {
  const Threads scope(threads());
  auto s = scene();
  auto reader = std::make_shared<Reader>();
  Simulation sim = chain(s, {reader});
  sim.run(10);
  ASSERT_EQ(reader->reads, 10);
  EXPECT_TRUE(reader->fused);
  ASSERT_TRUE(worthThreads(s->contacts.size()));
  ASSERT_GT(s->contacts.size(), 4 * kSumBlock);
  ASSERT_GT(s->bodies.size(), 2 * kSumBlock);
  long sliding = 0;
  for (const auto& e : sim.engines())
    if (auto f = std::dynamic_pointer_cast<ContactForces>(e)) sliding = f->slidingContacts;
  EXPECT_GT(sliding, 0);  // the shear forces include capped ones
  EXPECT_LE(reader->stress, test::kSameBits);
  EXPECT_LE(reader->stiffness, test::kSameBits);
  EXPECT_LE(reader->unbalanced, test::kSameBits);
}

// Summing the measures changes nothing of the motion: a run whose engine reads them every step
// and a run without any reader end in the same bits, and a step without a reader leaves no sums
// behind for a later reader to take as current.
TEST_P(FusedMeasures, ChangeNothingOfTheMotionAndAreOnlyMadeWhenRead) {
  const Threads scope(threads());
  auto a = scene(), b = scene();
  Simulation read = chain(a, {std::make_shared<Reader>()}), unread = chain(b, {});
  read.run(12);
  unread.run(12);
  for (int k = 0; k < a->bodies.size(); ++k) {
    ASSERT_EQ(a->bodies.pos[k], b->bodies.pos[k]) << "body " << k;
    ASSERT_EQ(a->bodies.angVel[k], b->bodies.angVel[k]) << "body " << k;
  }
  EXPECT_FALSE(b->measured.current(b->step));
  EXPECT_FALSE(b->measured.current(b->step - 1));
}

// A servo that reads the force loop's sums drives the cell as one that reads the separate pass:
// the same cell and positions after 20 steps of loading (the same bits on the baseline build).
TEST_P(FusedMeasures, DriveTheServoAsTheSeparatePass) {
  const Threads scope(threads());
  auto a = scene(), b = scene();
  const auto servo = [] {
    auto e = std::make_shared<TrueTriaxialServo>();
    e->goal = TrueTriaxialState{0.5, 140e3, 100e3};
    e->pathRate = 500;
    return e;
  };
  auto fused = servo(), separate = servo();
  fused->start(*a);
  separate->start(*b);
  Simulation sa = chain(a, {fused}), sb = chain(b, {std::make_shared<Unannounced>(separate)});
  sa.run(20);
  sb.run(20);
  ASSERT_EQ(fused->steps, 20);
  ASSERT_EQ(separate->steps, 20);
  EXPECT_FALSE(b->measured.current(b->step - 1));  // nothing was summed for the unannounced servo
  EXPECT_GT(a->cell.velGrad.norm(), 0.0);
  // 20 steps carry a difference of the last bit to a few more bits: 1e-12 of the cell's size.
  const Real tol = test::kSameBits == 0 ? 0.0 : 1e-12;
  EXPECT_LE((a->cell.hSize - b->cell.hSize).norm(), tol * b->cell.hSize.norm());
  Real worst = 0;
  for (int k = 0; k < a->bodies.size(); ++k) worst = std::max(worst, (a->bodies.pos[k] - b->bodies.pos[k]).norm());
  EXPECT_LE(worst, tol * b->cell.hSize.norm());
}

// One contact's terms: the Love-Weber term F (x) L, the diagonal of Eq. (32) of
// measure/ContactTerms.hpp and |F|.
TEST(CellTerms, AreTheContactTerms) {
  const Vec3 F(-3.5, 1.25, 7.0), L(1e-4, -2e-4, 0.5e-4), n = L.normalized();
  const Real kn = 2.5e5, ratio = 0.8;
  Real t[kCellTerms];
  int done = 0;
  cellTerms<Real>(F.x(), F.y(), F.z(), L.x(), L.y(), L.z(), n.x(), n.y(), n.z(), kn, ratio, t,
                  [](Real x) { return std::sqrt(x); }, [&](int g) { EXPECT_EQ(g, done++); });
  EXPECT_EQ(done, kCellTerms / 4);
  Mat3 stress = Mat3::Zero();
  addStressTerm(F, L, stress);
  Vec6 stiffness = Vec6::Zero();
  addAffineStiffnessTerm(kn, ratio, n, L, stiffness);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(t[3 * i + j], stress(i, j), test::kSameBits * stress.norm());
  for (int I = 0; I < 6; ++I) EXPECT_NEAR(t[9 + I], stiffness[I], test::kSameBits * stiffness.norm());
  EXPECT_NEAR(t[15], F.norm(), test::kSameBits * F.norm());
}

// Four contacts side by side, as the force loop adds them (measure/CellLanes.hpp), against the
// separate pass's sums of the loaded ones contact after contact: the same bits on the baseline. A
// contact without load (N = 0, its force and overlap as any other's, the signs of its branch mixed
// so that its terms include -0) leaves the sums' bits and is not counted; so do the lanes past a
// batch's last contact, whatever they hold (addCellTermsOf).
TEST(CellLanes, AddFourContactsAsTheSeparatePassAddsThem) {
  const Real ratio = 0.8;
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<Real> U(-1, 1);
  Real Fx[8], Fy[8], Fz[8], nx[8], ny[8], nz[8], N[8], delta[8];
  Vec3 L[8];  // read four at a time by loadVectorLanes
  for (int k = 0; k < 8; ++k) {
    L[k] = 1e-4 * Vec3(U(gen), U(gen), U(gen));
    const Vec3 n = L[k].normalized(), F = 10 * Vec3(U(gen), U(gen), U(gen));
    Fx[k] = F.x(); Fy[k] = F.y(); Fz[k] = F.z();
    nx[k] = n.x(); ny[k] = n.y(); nz[k] = n.z();
    N[k] = 5 + U(gen);
    delta[k] = 1e-6 * (2 + U(gen));
  }
  N[2] = 0;  // touching, without load
  L[2] = Vec3(-1e-4, 2e-4, -3e-4);
  for (int k = 6; k < 8; ++k)  // lanes past the last contact: they hold anything
    Fx[k] = Fy[k] = Fz[k] = nx[k] = ny[k] = nz[k] = N[k] = delta[k] = std::numeric_limits<Real>::quiet_NaN();
  L[6] = L[7] = Vec3::Constant(std::numeric_limits<Real>::infinity());
  CellLaneSums lanes;
  Lanes Lx, Ly, Lz;
  loadVectorLanes(L[0].data(), Lx, Ly, Lz);
  addCellTerms(loadLanes(Fx), loadLanes(Fy), loadLanes(Fz), Lx, Ly, Lz, loadLanes(nx), loadLanes(ny), loadLanes(nz),
               loadLanes(N), loadLanes(delta), ratio, lanes);
  loadVectorLanes(L[4].data(), Lx, Ly, Lz);
  for (int l = 0; l < kLanes; ++l) EXPECT_EQ(Vec3(Lx[l], Ly[l], Lz[l]), L[4 + l]) << "lane " << l;
  addCellTermsOf(2, loadLanes(Fx + 4), loadLanes(Fy + 4), loadLanes(Fz + 4), Lx, Ly, Lz, loadLanes(nx + 4),
                 loadLanes(ny + 4), loadLanes(nz + 4), loadLanes(N + 4), loadLanes(delta + 4), ratio, lanes);
  const CellSums fused = lanes.cellSums();
  CellSums separate;
  for (int k = 0; k < 6; ++k)
    if (N[k] > 0)
      separate.addContact(Vec3(Fx[k], Fy[k], Fz[k]), L[k], Vec3(nx[k], ny[k], nz[k]),
                          HertzMindlin::normalStiffness(N[k], delta[k]), ratio);
  EXPECT_EQ(separate.loaded, 5);
  EXPECT_EQ(fused.loaded, separate.loaded);
  for (int j = 0; j < kCellTerms; ++j) {
    EXPECT_NEAR(fused.sum[j], separate.sum[j], test::kSameBits * std::abs(separate.sum[j])) << "term " << j;
    EXPECT_FALSE(std::signbit(fused.sum[j]) && fused.sum[j] == 0) << "term " << j;
  }
  // A contact without load alone: every term +0 or -0, and the sums stay +0.
  CellLaneSums none;
  const Lanes zero = {}, one = {1, 1, 1, 1}, minus = -one;
  addCellTerms(one, minus, one, minus, one, minus, one, zero, zero, zero, one, ratio, none);
  const CellSums empty = none.cellSums();
  EXPECT_EQ(empty.loaded, 0);
  for (int j = 0; j < kCellTerms; ++j) {
    EXPECT_EQ(empty.sum[j], 0.0) << "term " << j;
    EXPECT_FALSE(std::signbit(empty.sum[j])) << "term " << j;
  }
}

INSTANTIATE_TEST_SUITE_P(SpheresAndClumpsOnOneAndTwoThreads, FusedMeasures,
                         ::testing::Combine(::testing::Bool(), ::testing::Values(1, 2)),
                         [](const ::testing::TestParamInfo<std::tuple<bool, int>>& info) {
                           return std::string(std::get<0>(info.param) ? "Clumps" : "Spheres") +
                                  std::to_string(std::get<1>(info.param)) + "Threads";
                         });
