// Fabric measures (Eqs. 14-16, 33-36) against a brute-force computation from positions alone,
// on hand-made configurations of spheres and of clumps with known contacts.
#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "FabricScenes.hpp"
#include "dynamics/Simulation.hpp"
#include "measure/Coordination.hpp"
#include "measure/Fabric.hpp"
#include "measure/Stress.hpp"
#include "measure/FabricRecorder.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

struct Reference {
  Mat3 R = Mat3::Zero(), H = Mat3::Zero(), B = Mat3::Zero();
  Real M[3][3][3][3] = {};
  Real meanN = 0;
  int Nc = 0;
};

// Eqs. (15), (16), (33), (34) term by term, four nested loops for M.
Reference reference(const std::vector<BruteContact>& cs) {
  Reference r;
  for (const BruteContact& c : cs) {
    const Real w = std::cbrt(c.rbar * c.N);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        r.R(i, j) += c.n[i] * c.n[j];
        r.H(i, j) += c.L[i] * c.L[j];
        r.B(i, j) += w * c.L[i] * c.L[j];
        for (int k = 0; k < 3; ++k)
          for (int l = 0; l < 3; ++l) r.M[i][j][k][l] += w * c.L[i] * c.n[j] * c.L[k] * c.n[l];
      }
    r.meanN += c.N;
  }
  r.Nc = static_cast<int>(cs.size());
  r.R /= r.Nc; r.H /= r.Nc; r.B /= r.Nc; r.meanN /= r.Nc;
  for (auto& a : r.M) for (auto& b : a) for (auto& c : b) for (Real& d : c) d /= r.Nc;
  return r;
}

// Relative to the tensor's largest component: every entry is a sum of <= 5 products of doubles
// (round-off ~1e-16 each); the overlaps come from distances ~1e-4 differing in the 4th digit,
// and the force law and the brute force compute them the same way, so 1e-12 is ample.
constexpr Real kTight = 1e-12;

void expectTensorsMatch(const Fabric& f, const Reference& r) {
  EXPECT_EQ(f.counts.contacts, r.Nc);
  EXPECT_LT((f.R - r.R).cwiseAbs().maxCoeff(), kTight * r.R.cwiseAbs().maxCoeff());
  EXPECT_LT((f.H - r.H).cwiseAbs().maxCoeff(), kTight * r.H.cwiseAbs().maxCoeff());
  EXPECT_LT((f.B - r.B).cwiseAbs().maxCoeff(), kTight * r.B.cwiseAbs().maxCoeff());
  Real scale = 0, err = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) {
          scale = std::max(scale, std::abs(r.M[i][j][k][l]));
          err = std::max(err, std::abs(f.M4(i, j, k, l) - r.M[i][j][k][l]));
        }
  EXPECT_LT(err, kTight * scale);
  EXPECT_NEAR(f.meanNormalForce, r.meanN, kTight * r.meanN);
}

// What Eq. (34) implies whatever the particle shape: major symmetry, and contraction over the
// normal's indices gives B because n is a unit vector (Sum_j M_ijkj = B_ik).
void expectMSymmetries(const Fabric& f) {
  const Real scale = f.M.cwiseAbs().maxCoeff();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) EXPECT_EQ(f.M4(i, j, k, l), f.M4(k, l, i, j));
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const Real contracted = f.M4(i, 0, k, 0) + f.M4(i, 1, k, 1) + f.M4(i, 2, k, 2);
      // |n|^2 = 1 to ~2e-16 per contact
      EXPECT_NEAR(contracted, f.B(i, k), 1e-14 * f.B.cwiseAbs().maxCoeff());
    }
  EXPECT_NEAR(f.R.trace(), 1.0, 1e-15);  // Eq. (15): each term has trace |n|^2 = 1
  EXPECT_GT(scale, 0);
}

}  // namespace

TEST(Fabric, HandMadeSpheresMatchBruteForce) {
  auto s = handSpheres();
  evaluateContacts(*s);
  const auto cs = bruteContacts(*s);
  ASSERT_EQ(cs.size(), 5u);  // A-B, A-C, B-C, C-D, D-F
  int periodic = 0;
  for (int c = 0; c < s->contacts.size(); ++c) periodic += s->contacts.active(c) && !s->contacts.shift[c].isZero();
  ASSERT_GT(periodic, 0);  // the configuration does exercise the periodic image
  const Fabric f = fabric(*s);
  expectTensorsMatch(f, reference(cs));
  expectMSymmetries(f);
  // Spheres: L is parallel to n, so M is also symmetric within each index pair.
  const Real scale = f.M.cwiseAbs().maxCoeff();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) EXPECT_NEAR(f.M4(i, j, k, l), f.M4(j, i, k, l), 1e-12 * scale);
}

// Eq. (14) by hand: counts A2 B2 C3 D2 E0 F1, so Nc = 5, Np = 6, Np^0 = 1 (E), Np^1 = 1 (F) and
// Zm = (2*5 - 1)/(6 - 1 - 1) = 9/4, while the plain 2Nc/Np = 5/3 counts E and F.
TEST(Fabric, MechanicalCoordinationFollowsEq14) {
  auto s = handSpheres();
  evaluateContacts(*s);
  const Fabric f = fabric(*s);
  EXPECT_EQ(f.counts.contacts, 5);
  EXPECT_EQ(f.counts.particles, 6);
  EXPECT_EQ(f.counts.noContact, 1);
  EXPECT_EQ(f.counts.oneContact, 1);
  EXPECT_DOUBLE_EQ(f.Zm, 9.0 / 4.0);
  EXPECT_EQ(f.Zm, coordination(*s).mechanical());  // same counts as the incidence-list route
}

// Void ratio and Nc/V by hand from the radii: e = (V - sum 4/3 pi r^3)/sum, Eq. (36) with the mean
// r^3, and the identity Eq. (36) = Zm Np / (2 V) that holds when r^3 and e share the solid volume.
TEST(Fabric, ContactDensityAndVoidRatio) {
  auto s = handSpheres();
  evaluateContacts(*s);
  const Fabric f = fabric(*s);
  Real vs = 0, r3 = 0;
  for (Real r : s->members.radius) { vs += 4.0 / 3.0 * M_PI * r * r * r; r3 += r * r * r; }
  r3 /= s->bodies.size();
  const Real V = s->cell.volume(), e = (V - vs) / vs;
  // masses round-trip through rho (4/3) pi r^3: a few ulps
  EXPECT_NEAR(f.voidRatio, e, 1e-13 * e);
  EXPECT_NEAR(f.meanRadiusCubed, r3, 1e-14 * r3);
  EXPECT_NEAR(f.contactDensityEq36(), 3 * (9.0 / 4.0) / (8 * M_PI * (1 + e) * r3), 1e-13 * f.contactDensityEq36());
  EXPECT_NEAR(f.contactDensityEq36(), f.Zm * 6 / (2 * V), 1e-13 * f.contactDensityEq36());
  EXPECT_DOUBLE_EQ(f.contactDensityCount(), 5 / V);
}

// Clumps: a particle is a body, L joins body centres, rbar comes from the members in contact and
// each member-member contact counts. dimer1 has 3 contacts, dimer2 2, the sphere 1:
// Nc = 3, Np = 3, Np^0 = 0, Np^1 = 1, Zm = (6 - 1)/(3 - 0 - 1) = 5/2.
TEST(Fabric, TwoClumpsMatchBruteForce) {
  auto s = twoClumps();
  evaluateContacts(*s);
  const auto cs = bruteContacts(*s);
  ASSERT_EQ(cs.size(), 3u);
  const Fabric f = fabric(*s);
  expectTensorsMatch(f, reference(cs));
  expectMSymmetries(f);
  EXPECT_EQ(f.counts.particles, 3);
  EXPECT_EQ(f.counts.noContact, 0);
  EXPECT_EQ(f.counts.oneContact, 1);
  EXPECT_DOUBLE_EQ(f.Zm, 2.5);
  // By hand: the two dimer-dimer contacts have L = (0, 2r - delta, 0), the sphere's branch from
  // the dimer's centre is (d, 0, 0) + (r + r3 - delta3) u (FabricScenes.hpp).
  const Real Ly = 2e-4 - 3e-7;
  const Vec3 Ls = Vec3(0.8e-4, 0, 0) + (1.7e-4 - 2e-7) * Vec3(1, -1, 0.5).normalized();
  const Mat3 H = (2 * Vec3(0, Ly, 0) * Vec3(0, Ly, 0).transpose() + Ls * Ls.transpose()) / 3;
  EXPECT_LT((f.H - H).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
  // The oblique sphere contact makes L and n non-coaxial: M loses the within-pair symmetry.
  Real asym = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l < 3; ++l) asym = std::max(asym, std::abs(f.M4(i, j, k, l) - f.M4(j, i, k, l)));
  EXPECT_GT(asym, 0.01 * f.M.cwiseAbs().maxCoeff());
  // Eq. (36) with the equal-volume radius of each clump, r^3 = 3 V_b / (4 pi), V_b the union's
  // volume (the overlap of the dimer's members counted once).
  Real r3 = 0;
  for (int b = 0; b < 3; ++b) r3 += 3 * s->bodies.volume[b] / (4 * M_PI);
  EXPECT_LT(s->bodies.volume[0], 0.98 * 2 * 4.0 / 3.0 * M_PI * 1e-12);  // the members overlap (by 3 %)
  EXPECT_NEAR(f.meanRadiusCubed, r3 / 3, 1e-14 * r3);
}

// Block sums: the same bits whatever the number of threads.
TEST(Fabric, IndependentOfThreadCount) {
#ifdef _OPENMP
  auto s = randomGas(3000, 0.62, 5, true);
  evaluateContacts(*s);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const Fabric one = fabric(*s);
  omp_set_num_threads(3);
  const Fabric three = fabric(*s);
  omp_set_num_threads(saved);
  ASSERT_GT(one.counts.contacts, 2000);  // several blocks of 512
  EXPECT_EQ(one.M, three.M);
  EXPECT_EQ(one.B, three.B);
  EXPECT_EQ(one.R, three.R);
  EXPECT_EQ(one.Zm, three.Zm);
#else
  GTEST_SKIP() << "built without OpenMP";
#endif
}

// A dense random dimer network: brute force over ~6000 member pairs in contact.
TEST(Fabric, RandomClumpNetworkMatchesBruteForce) {
  auto s = randomGas(600, 0.6, 9, true);
  evaluateContacts(*s);
  const auto cs = bruteContacts(*s);
  ASSERT_GT(cs.size(), 500u);
  const Fabric f = fabric(*s);
  // Sums of ~1000 terms: round-off grows like sqrt(n) eps; 1e-12 still holds with margin.
  expectTensorsMatch(f, reference(cs));
  expectMSymmetries(f);
  EXPECT_EQ(f.Zm, coordination(*s).mechanical());
}

TEST(Fabric, RefusesContactsNotEvaluatedHere) {
  auto s = handSpheres();
  EXPECT_THROW(fabric(*s), InputError);  // nothing detected yet
  evaluateContacts(*s);
  s->detectionInvalid = true;            // bodies moved since
  EXPECT_THROW(fabric(*s), InputError);
  s->detectionInvalid = false;
  s->contacts.evaluation.pos.clear();    // an imported history without a force evaluation
  s->contacts.normalForce[0] = 1.0;
  EXPECT_THROW(fabric(*s), InputError);
  EXPECT_THROW(loveWeberStress(*s), InputError);  // no branch vectors: not a stress of zeros
  s->contacts.normalForce.assign(s->contacts.size(), 0.0);
  EXPECT_EQ(loveWeberStress(*s), Mat3::Zero());  // nothing loaded: nothing to refuse
}

TEST(Fabric, NoContactsGiveNaNNotACrash) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  s->cell.setBox(Vec3::Constant(1e-3));
  s->addSphere(Vec3::Constant(5e-4), 1e-4);
  evaluateContacts(*s);
  const Fabric f = fabric(*s);
  EXPECT_EQ(f.counts.contacts, 0);
  EXPECT_TRUE(std::isnan(f.Zm));
  EXPECT_TRUE(std::isnan(f.R(0, 0)));
  EXPECT_TRUE(std::isnan(f.contactDensityEq36()));
}

// Records at steps 0, 3, 6, 9 of a 10-step run (engine every 3); no integrator, so nothing moves
// and every record equals the fabric measured afterwards. Flattening order checked on an
// asymmetric M entry.
TEST(FabricRecorder, RecordsEveryNStepsInCOrder) {
  auto s = twoClumps();
  Simulation sim(s);
  sim.add(std::make_shared<ContactDetection>());
  sim.add(std::make_shared<ContactForces>());
  auto rec = std::make_shared<FabricRecorder>();
  rec->every = 3;
  sim.add(rec);
  sim.run(10);
  const FabricHistory& h = rec->history;
  ASSERT_EQ(h.size(), 4);
  EXPECT_EQ(h.step, (std::vector<long>{0, 3, 6, 9}));
  const Fabric f = fabric(*s);
  for (int r = 0; r < 4; ++r) {
    EXPECT_EQ(h.Zm[r], f.Zm);
    EXPECT_EQ(h.contacts[r], 3);
    EXPECT_EQ(h.B[9 * r + 3 * 1 + 0], f.B(1, 0));
    EXPECT_EQ(h.M[81 * r + 27 * 0 + 9 * 1 + 3 * 2 + 0], f.M4(0, 1, 2, 0));
    EXPECT_EQ(h.M[81 * r + 27 * 2 + 9 * 0 + 3 * 0 + 1], f.M4(2, 0, 0, 1));
    EXPECT_EQ(h.contactDensityEq36[r], f.contactDensityEq36());
  }
  EXPECT_EQ(rec->last.M, f.M);
}
