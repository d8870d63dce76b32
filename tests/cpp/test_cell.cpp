// The fully deformable periodic cell: contact detection in a sheared cell against a brute-force
// search over image pairs (shear strains up to 0.3 and through a flip), the flip keeping every
// contact's history, the same periodic medium described by two different cell matrices giving the
// same forces, the cell's strain measure, and bad cell matrices refused.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "Drivers.hpp"
#include "RandomGas.hpp"
#include "Lattices.hpp"
#include "control/StressProbe.hpp"
#include "dynamics/TimeStepper.hpp"
#include "statics/StaticStiffness.hpp"
#include "dynamics/CellFlip.hpp"
#include "dynamics/ContactRefresh.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "measure/Stress.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

using PairKey = std::tuple<int, int, int, int, int>;  // m1 < m2, image shift of m2

// A random gas in the cell `shape` (RandomGas.hpp) with a time step set.
std::shared_ptr<Scene> gasIn(const Mat3& shape, int n, Real phi, unsigned seed, Real r = 1e-4) {
  auto s = randomGasIn(shape, n, phi, seed, r);
  s->dt = 1e-9;
  return s;
}

// Stretch the scene axis by axis (bodies and cell, radii kept) so that each diagonal entry of
// hSize holds a whole number of interaction ranges plus 2 %: a contact grid sized by those entries
// instead of the face distances of the sheared cell would then have bins thinner than the range,
// and miss pairs. (Random spheres rarely sit where a slightly thin bin fails; tight bins make the
// tests below fail on such a grid.)
void tightBins(Scene& s, Real skinFactor) {
  const Real range = (2.0 + skinFactor) * s.maxRadius();
  Vec3 f;
  for (int k = 0; k < 3; ++k) f[k] = (std::floor(s.cell.hSize(k, k) / range) + 0.02) * range / s.cell.hSize(k, k);
  for (Vec3& p : s.bodies.pos) p = f.cwiseProduct(p);
  s.refreshMembers();
  s.cell.hSize = f.asDiagonal() * s.cell.hSize;
  s.cell.refHSize = s.cell.hSize;
}

// Every touching pair over images k in [-2, 2]^3 (positions lie within one cell of the cell they were wrapped into), from the lower member index, with the force
// loop's own distance expression (so the comparison is exact).
// With skin > 0: every pair closer than r_i + r_j + skin (what a fresh Verlet list must hold).
std::set<PairKey> bruteContacts(const Scene& s, Real skin = 0) {
  std::set<PairKey> out;
  const Members& M = s.members;
  const Mat3& h = s.cell.hSize;
  for (int i = 0; i < M.size(); ++i)
    for (int j = i + 1; j < M.size(); ++j) {
      const Real rs = M.radius[i] + M.radius[j] + skin;
      for (int a = -2; a <= 2; ++a)
        for (int b = -2; b <= 2; ++b)
          for (int c = -2; c <= 2; ++c) {
            const Vec3i k(a, b, c);
            const Vec3 d = (M.pos[j] + Vec3(h * k.cast<Real>())) - M.pos[i];
            if (d.squaredNorm() < rs * rs) out.insert({i, j, a, b, c});
          }
    }
  return out;
}

// The active contacts of the last force evaluation (all listed pairs with `all`); fails the test
// on a pair listed twice.
std::set<PairKey> listedContacts(const Scene& s, bool all = false) {
  std::set<PairKey> out;
  const Contacts& C = s.contacts;
  for (int c = 0; c < C.size(); ++c) {
    if (!all && !C.active(c)) continue;
    const bool fresh = out.insert({C.m1[c], C.m2[c], C.shift[c].x(), C.shift[c].y(), C.shift[c].z()}).second;
    EXPECT_TRUE(fresh) << "pair " << C.m1[c] << "-" << C.m2[c] << " listed twice";
  }
  return out;
}

Mat3 simpleShear(int i, int j, Real gamma) {
  Mat3 m = Mat3::Identity();
  m(i, j) = gamma;
  return m;
}

// Carry the whole scene by the affine map A (bodies and cell), as the integrator's affine part does.
void deformAffinely(Scene& s, const Mat3& A) {
  for (Vec3& p : s.bodies.pos) p = A * p;
  s.refreshMembers();
  s.cell.hSize = A * s.cell.hSize;
}

void expectSameSets(const std::set<PairKey>& brute, const std::set<PairKey>& listed, const std::string& where) {
  EXPECT_GT(brute.size(), 100u) << where;
  std::vector<PairKey> missed, extra;
  std::set_difference(brute.begin(), brute.end(), listed.begin(), listed.end(), std::back_inserter(missed));
  std::set_difference(listed.begin(), listed.end(), brute.begin(), brute.end(), std::back_inserter(extra));
  EXPECT_TRUE(missed.empty()) << where << ": " << missed.size() << " contacts missed";
  EXPECT_TRUE(extra.empty()) << where << ": " << extra.size() << " contacts that do not touch";
}

void expectSameContacts(const Scene& s, const std::string& where) {
  expectSameSets(bruteContacts(s), listedContacts(s), where);
}

}  // namespace

// Freshly built lists in cells sheared by 0.3 in each of the six planes and in a general
// (triclinic) cell: exactly the touching pairs over all images, none twice; and the list itself
// holds exactly the pairs within reach (r_i + r_j + skin), which is what a grid with bins thinner
// than the range would get wrong first.
TEST(ShearedCell, DetectionFindsExactlyTheTouchingImagePairs) {
  std::vector<std::pair<std::string, Mat3>> shapes;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j) shapes.push_back({"shear " + std::to_string(i) + std::to_string(j), simpleShear(i, j, 0.3)});
  Mat3 triclinic;
  triclinic << 1.0, 0.2, -0.1, 0.15, 0.9, 0.25, -0.2, 0.1, 1.1;
  shapes.push_back({"triclinic", triclinic});
  // Beyond the flip threshold with flips off: a cell sheared by 1 in two planes still detects right.
  shapes.push_back({"unreduced", simpleShear(0, 2, 1.0) * simpleShear(1, 0, -1.0)});
  for (const auto& [name, shape] : shapes) {
    auto s = gasIn(shape, 300, 0.55, 7);
    Driver drv(s);
    drv.detection().allowFlip = name != "unreduced";
    tightBins(*s, drv.detection().skinFactor);
    drv.evaluate();
    EXPECT_EQ(drv.detection().flips, 0) << name;  // no flip needed at 0.3
    expectSameContacts(*s, name);
    const Real skin = drv.detection().skinFactor * s->maxRadius();
    expectSameSets(bruteContacts(*s, skin), listedContacts(*s, true), name + " (list within reach)");
  }
}

// A cell sheared step by step from 0 to 0.8 in the xz plane (flip at 0.55), the list rebuilt only
// when the skin criterion asks: at every step the force loop sees exactly the touching pairs, the
// flip happens once, and no active contact is ever lost at a rebuild.
TEST(ShearedCell, VerletListStaysValidWhileShearingAndThroughAFlip) {
  auto s = gasIn(Mat3::Identity(), 300, 0.55, 11);
  Driver drv(s);
  drv.detection().skinFactor = 0.2;
  tightBins(*s, 0.2);
  const int steps = 80;
  const Mat3 A = simpleShear(0, 2, 0.01);  // gamma += 0.01 per step (x displaced along z)
  long checked = 0, flipSeen = 0;
  for (int k = 0; k <= steps; ++k) {
    drv.evaluate();
    if (k % 8 == 0 || (drv.detection().flips == 1 && flipSeen++ < 2)) {
      expectSameContacts(*s, "gamma " + std::to_string(0.01 * k));
      ++checked;
    }
    deformAffinely(*s, A);
    for (int b = 0; b < s->bodies.size(); ++b) s->bodies.pos[b] += Vec3(1e-6 * std::sin(b), 1e-6 * std::cos(3.0 * b), 0);
    s->refreshMembers();
  }
  EXPECT_EQ(drv.detection().flips, 1);
  EXPECT_EQ(drv.detection().lostContacts, 0);
  EXPECT_GT(drv.detection().rebuilds, 5);
  EXPECT_LT(drv.detection().rebuilds, steps);  // rebuilt when needed, not every step
  // After the flip the cell vector a_3 = (gamma, 0, 1) L became (gamma - 1, 0, 1) L.
  EXPECT_NEAR(s->cell.hSize(0, 2) / s->cell.hSize(2, 2), 0.01 * (steps + 1) - 1.0, 1e-9);
  EXPECT_GT(checked, 10);
}

// A flip by itself (positions unchanged): the same contacts with the same branch vectors, normal
// and tangential forces carried (to round-off: the rebuild wraps the bodies into the new cell, which
// moves them by whole cell vectors), the deformation gradient and the volume unchanged.
TEST(ShearedCell, FlipKeepsEveryContactAndItsHistory) {
  auto s = gasIn(simpleShear(1, 2, 0.62), 250, 0.6, 3);
  s->cell.refHSize = s->cell.hSize.diagonal().asDiagonal();  // strain measured from the unsheared cell
  ContactDetection detection;
  detection.allowFlip = false;
  auto evaluate = [&](Real dt) {
    detection.rebuild(*s);
    s->detectionInvalid = false;
    const Real saved = s->dt;
    s->dt = dt;
    ContactForces().apply(*s);
    s->dt = saved;
  };
  // Load tangential springs: one shear increment with dt > 0, then the state at rest (dt = 0).
  s->cell.velGrad.setZero();
  s->cell.velGrad(0, 1) = 50.0;
  evaluate(s->dt);
  s->cell.velGrad.setZero();
  evaluate(0.0);
  const Scene before = *s;
  long loaded = 0;
  for (int c = 0; c < before.contacts.size(); ++c) loaded += before.contacts.shearForce[c].norm() > 0;
  ASSERT_GT(loaded, 100);

  const Mat3i M = flipIfSheared(*s, 0.55);
  ASSERT_NE(M, Mat3i::Identity());
  EXPECT_EQ(M(1, 2), -1);
  EXPECT_LT(std::abs(s->cell.hSize(1, 2)), 0.5 * s->cell.hSize(1, 1));
  EXPECT_LT((s->cell.deformation() - before.cell.deformation()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_NEAR(s->cell.volume(), before.cell.volume(), 1e-12 * before.cell.volume());
  evaluate(0.0);
  std::map<std::tuple<int, int>, std::vector<int>> byPair;
  for (int c = 0; c < s->contacts.size(); ++c) byPair[{s->contacts.m1[c], s->contacts.m2[c]}].push_back(c);
  long matched = 0, active = 0;
  for (int c = 0; c < before.contacts.size(); ++c) {
    if (!before.contacts.active(c)) continue;
    ++active;
    const Vec3& L = before.contacts.branch(c);
    bool found = false;
    for (int d : byPair[{before.contacts.m1[c], before.contacts.m2[c]}]) {
      if ((s->contacts.branch(d) - L).norm() > 1e-9 * L.norm()) continue;  // another image of the pair
      found = true;
      const Real N = before.contacts.normalForce[c];
      EXPECT_NEAR(s->contacts.normalForce[d], N, 1e-6 * N);  // delta ~ 1e-3 L: 1e-16 of L is 1e-13 of delta
      EXPECT_LT((s->contacts.shearForce[d] - before.contacts.shearForce[c]).norm(), 1e-9 * N);
    }
    EXPECT_TRUE(found) << "contact " << c;
    matched += found;
  }
  EXPECT_EQ(matched, active);
  long after = 0;
  for (int c = 0; c < s->contacts.size(); ++c) after += s->contacts.active(c);
  EXPECT_EQ(after, active);
  EXPECT_GT(active, 300);
  // A contact refresh flips a cell that needs it on its own (ContactDetection's default).
  auto t = gasIn(simpleShear(1, 2, 0.62), 250, 0.6, 3);
  refreshContacts(*t);
  EXPECT_LT(std::abs(t->cell.hSize(1, 2)), 0.5 * t->cell.hSize(1, 1));
}

// The same periodic medium described by two cell matrices (h and h M, M unimodular: the second
// cell's vectors are sheared combinations of the first's) is one physical system: every body gets
// the same force, the Love-Weber stress is the same tensor, and after 200 steps of dynamics under
// the same velocity gradient the bodies are in the same places (round-off apart). The
// orthorhombic and the sheared code paths are compared on one scene.
TEST(ShearedCell, TwoDescriptionsOfOneMediumAgree) {
  auto ortho = gasIn(Mat3(Vec3(1.0, 1.1, 0.9).asDiagonal()), 300, 0.62, 5);
  auto sheared = std::make_shared<Scene>(*ortho);
  Mat3i M;
  M << 1, 0, 1, 0, 1, -1, 0, 0, 1;
  sheared->cell.hSize = ortho->cell.hSize * M.cast<Real>();
  sheared->cell.refHSize = ortho->cell.refHSize * M.cast<Real>();
  ASSERT_FALSE(sheared->cell.orthorhombic());
  Mat3 L = Mat3::Zero();
  L(0, 0) = -2.0;
  L(2, 2) = 1.0;  // diagonal: the orthorhombic description keeps its fast path
  std::vector<std::shared_ptr<Scene>> both = {ortho, sheared};
  for (auto& s : both) {
    s->cell.velGrad = L;
    auto sim = std::make_shared<Simulation>(s);
    auto detection = std::make_shared<ContactDetection>();
    detection->allowFlip = false;
    sim->add(detection);
    sim->add(std::make_shared<ContactForces>());
    auto newton = std::make_shared<NewtonIntegrator>();
    newton->damping = 0.3;
    sim->add(newton);
    sim->run(200);
  }
  ASSERT_TRUE(ortho->cell.orthorhombic());
  ASSERT_FALSE(sheared->cell.orthorhombic());
  const Mat3 s1 = loveWeberStress(*ortho), s2 = loveWeberStress(*sheared);
  EXPECT_GT(s1.norm(), 0);
  EXPECT_LT((s1 - s2).norm(), 1e-9 * s1.norm());
  Real worst = 0, scale = 0;
  for (int b = 0; b < ortho->bodies.size(); ++b) {
    // Positions are wrapped differently by the two cells: compare modulo the first cell's lattice.
    Vec3 d = sheared->bodies.pos[b] - ortho->bodies.pos[b];
    const Vec3 k = (ortho->cell.hSize.inverse() * d).array().round();
    d -= ortho->cell.hSize * k;
    worst = std::max(worst, d.norm());
    scale = std::max(scale, (ortho->bodies.force[b] - sheared->bodies.force[b]).norm() /
                                std::max(ortho->bodies.force[b].norm(), 1e-30));
  }
  EXPECT_LT(worst, 1e-12 * ortho->cell.hSize(0, 0));
  EXPECT_LT(scale, 1e-6);
}

// strainBetween: the log strain of a diagonal deformation exactly; a small simple shear gives its
// engineering shear strain (compression positive: gamma_xz = -2 E_xz); a rigid rotation none.
TEST(ShearedCell, StrainMeasure) {
  const Mat3 F0 = Vec3(1.0, 1.2, 0.9).asDiagonal();
  const Mat3 F1 = Vec3(1.01, 1.19, 0.95).asDiagonal();
  const Vec6 e = strainBetween(F0, F1);
  EXPECT_EQ(e[0], -std::log(1.01 / 1.0));
  EXPECT_EQ(e[1], -std::log(1.19 / 1.2));
  EXPECT_EQ(e[3], 0.0);
  const Real g = 1e-6;
  const Vec6 shear = strainBetween(F0, simpleShear(0, 2, g) * F0);
  EXPECT_NEAR(shear[4], -g, 1e-15);  // gamma_xz = E_xz + E_zx = g, extension positive
  EXPECT_LT(shear.head<3>().cwiseAbs().maxCoeff(), 1e-15);  // round-off of log near I
  const Mat3 R = Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_LT(strainBetween(Mat3::Identity(), R).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(unimodularInverse((Mat3i() << 1, 0, 1, 0, 1, -1, 0, 0, 1).finished()) *
                (Mat3i() << 1, 0, 1, 0, 1, -1, 0, 0, 1).finished(),
            Mat3i::Identity());
}

// A singular or inverted cell matrix is refused with a message saying which, before any work.
TEST(ShearedCell, RefusesSingularAndInvertedCells) {
  auto s = gasIn(Mat3::Identity(), 50, 0.3, 1);
  const Mat3 good = s->cell.hSize;
  auto message = [&](const Mat3& h) {
    s->cell.hSize = h;
    try {
      s->validate();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  Mat3 coplanar = good;
  coplanar.col(2) = good.col(0) + good.col(1);
  EXPECT_NE(message(coplanar).find("singular"), std::string::npos) << message(coplanar);
  Mat3 inverted = good;
  inverted.col(2) *= -1.0;
  EXPECT_NE(message(inverted).find("inverted"), std::string::npos) << message(inverted);
  Mat3 nan = good;
  nan(0, 1) = std::nan("");
  EXPECT_NE(message(nan).find("non-finite"), std::string::npos);
  EXPECT_EQ(message(good), "");
  s->cell.refHSize = inverted;
  EXPECT_NE(message(good).find("refHSize"), std::string::npos);
  s->cell.refHSize = good;
  // A cell sheared so far that it is thinner than the interaction range is refused at detection
  // (with flips switched off; with flips it is re-mapped instead).
  s->cell.hSize = good;
  s->cell.hSize(0, 2) = 5.0 * good(2, 2);  // face distance along x: 1/sqrt(26) of the edge
  ContactDetection detection;
  detection.allowFlip = false;
  try {
    detection.rebuild(*s);
    ADD_FAILURE() << "a cell thinner than the interaction range was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("thinner than the interaction range"), std::string::npos) << e.what();
  }
  detection.allowFlip = true;
  EXPECT_NO_THROW(detection.rebuild(*s));
  EXPECT_EQ(detection.flips, 1);
}

// Simple shears of 1 alternating between the xz and zx planes (F = (S_xz S_zx)^n, whose lattice maps
// onto itself), the cell flipped whenever detection would: hSize stays nearly orthogonal while
// refHSize, mapped by every flip, skews as 2.6^n. After 16 legs (skewness of refHSize 5e-7, a check
// on its vectors refused it as singular below 1e-6) the cell is valid and F = hSize refHSize^-1 is
// still the motion; sheared on, it is refused where F's round-off would pass about 2e-7, saying so;
// and a reference whose lattice is degenerate or inverted is still refused as such.
TEST(ShearedCell, ManyFlipsKeepTheReferenceCellValid) {
  Cell cell;
  cell.setBox(Vec3(1.0, 1.1, 0.9));
  Mat3 motion = Mat3::Identity();
  auto skewness = [](const Mat3& h) { return h.determinant() / (h.col(0).norm() * h.col(1).norm() * h.col(2).norm()); };
  auto message = [](const Cell& c) {
    try {
      c.validate();
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  int flips = 0, leg = 0;
  std::string refused;
  Cell lastValid;
  Mat3 lastMotion;
  for (; leg < 40 && refused.empty(); ++leg) {
    const Mat3 step = leg % 2 == 0 ? simpleShear(0, 2, 0.1) : simpleShear(2, 0, 0.1);
    for (int k = 0; k < 10 && refused.empty(); ++k) {
      cell.hSize = step * cell.hSize;
      motion = step * motion;
      const Mat3i M = cell.reduction(0.55);
      if (M != Mat3i::Identity()) {
        cell.flip(M);
        ++flips;
      }
      refused = message(cell);
      if (refused.empty()) {
        lastValid = cell;
        lastMotion = motion;
      }
    }
    if (leg == 15) {
      ASSERT_EQ(refused, "") << "after 16 legs";
      EXPECT_LT(skewness(cell.refHSize), 1e-6) << "the flips did not skew the reference cell as far as they should";
      EXPECT_GT(skewness(cell.hSize), 0.5);
      EXPECT_GT(flips, 16);
      EXPECT_LT((cell.deformation() - motion).norm(), 1e-8 * motion.norm());
    }
  }
  EXPECT_GT(leg, 20);
  EXPECT_NE(refused.find("refHSize has vectors so skewed"), std::string::npos) << refused;
  EXPECT_NE(refused.find("round-off"), std::string::npos) << refused;
  EXPECT_LT((lastValid.deformation() - lastMotion).norm(), 2e-6 * lastMotion.norm());
  EXPECT_NEAR(lastValid.refHSize.determinant(), 1.0 * 1.1 * 0.9, 1e-6);

  Cell bad = lastValid;
  bad.refHSize.col(2) = bad.refHSize.col(0) + bad.refHSize.col(1);  // coplanar
  EXPECT_NE(message(bad).find("refHSize is singular"), std::string::npos) << message(bad);
  bad.refHSize = lastValid.refHSize;
  bad.refHSize.col(1).setZero();
  EXPECT_NE(message(bad).find("refHSize is singular"), std::string::npos) << message(bad);
  bad.refHSize = Mat3::Identity();
  bad.refHSize.col(2) = Vec3(0.3, 0.4, 1e-12);  // nearly coplanar: F would be mostly round-off
  EXPECT_NE(message(bad).find("refHSize has vectors so skewed"), std::string::npos) << message(bad);
  bad.refHSize = lastValid.refHSize;
  bad.refHSize.col(2) *= -1.0;
  EXPECT_NE(message(bad).find("refHSize is inverted"), std::string::npos) << message(bad);
  bad.refHSize = lastValid.refHSize;
  bad.refHSize(1, 1) = std::numeric_limits<Real>::infinity();
  EXPECT_NE(message(bad).find("refHSize has non-finite"), std::string::npos) << message(bad);
}

TEST(ShearedCell, AFlipBeyondWholeNumbersIsRefused) {
  // Vector 2 leans 1e10 lengths of vector 1 along it: the rounded multiple is beyond an int.
  Cell cell;
  cell.hSize << 1e-10, 1.0, 0.0,
                0.0, 1.0, 0.0,
                0.0, 0.0, 1.0;
  try {
    cell.reduction(0.55);
    FAIL() << "a flip of 1e10 times a vector was not refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("too unequal to flip"), std::string::npos) << e.what();
  }
  // 1e6 times is within an int, and flips to the orthogonal basis.
  cell.hSize(0, 0) = 1e-6;
  const Mat3i M = cell.reduction(0.55);
  EXPECT_EQ(M(0, 1), -1000000);
}

// The affine field of a full velocity gradient in the force loop: a simple cubic lattice (spacing
// a, k_s of its contacts) under L = g e_x (x) e_z (v_x = g z), one force evaluation over dt with
// rotations blocked. Only the z-contacts slide, by g a dt along x (the image contacts across the
// cell's z faces included), so sigma_xz = k_s g dt a^2 / a^3 in magnitude and sigma_zx = 0; with
// the orthorhombic path (L's off-diagonal ignored) both would be zero.
TEST(ShearedCell, AffineVelocityOfAFullGradient) {
  const Real r = 1e-4, delta = 2e-7, a = 2 * r - delta;
  const int n = 3;
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial(1e23);
  s->cell.setBox(Vec3::Constant(n * a));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) s->addSphere(Vec3(i + 0.5, j + 0.5, k + 0.5) * a, r);
  s->blockRotations = true;
  s->dt = 1e-8;
  refreshContacts(*s);
  const Real g = 10.0;
  s->cell.velGrad(0, 2) = g;
  ASSERT_FALSE(s->cell.orthorhombic());
  ContactForces().apply(*s);
  const HertzMindlin law(s->material);
  const Real N = law.normalForce(delta, r), ks = law.shearStiffness(HertzMindlin::normalStiffness(N, delta));
  const Mat3 sigma = loveWeberStress(*s);
  EXPECT_NEAR(std::abs(sigma(0, 2)), ks * g * s->dt * a * a / (a * a * a), 1e-9 * ks * g * s->dt / a);
  EXPECT_EQ(sigma(2, 0), 0.0);
  long sliding = 0;
  for (int c = 0; c < s->contacts.size(); ++c)
    if (s->contacts.active(c) && s->contacts.shearForce[c].norm() > 0) {
      ++sliding;
      EXPECT_NEAR(std::abs(s->contacts.normal[c].z()), 1.0, 1e-12);  // only z-contacts slide
    }
  EXPECT_EQ(sliding, n * n * n);
}

// The FCC lattice in the sheared cell of its primitive vectors (60 degrees apart): the same
// lattice as the conventional cubic description, so the static stiffness is the closed form of
// docs/studies/statics.md, "FCC", in the cube axes, C_44 = sqrt2/l ((k_n + k_s)/2 - 3N/(2l)) included. Checks
// the images, the volume and the Love-Weber sum of a non-orthogonal cell through the statics.
// Tolerance as for the orthorhombic lattices (1e-9: round-off of the sparse solve).
TEST(ShearedCell, FaceCentredCubicInItsPrimitiveCellHasTheClosedForm) {
  const Real delta = 4e-7;
  auto s = fccPrimitive(3, delta);
  ASSERT_FALSE(s->cell.orthorhombic());
  const Mat6 C = fccStiffness(s->material, delta);
  for (bool rot : {false, true}) {
    StaticStiffness st;
    st.rotations = rot;
    const StaticStiffnessResult r = st.compute(*s);
    EXPECT_EQ(r.contacts, 27 * 6);
    EXPECT_LT((r.C - C).cwiseAbs().maxCoeff() / C.cwiseAbs().maxCoeff(), 1e-9) << "rotations=" << rot << "\n" << r.C;
    EXPECT_NEAR(r.constants.G[0] / C(3, 3), 1.0, 1e-9);
  }
}

namespace {

// A dynamic probe on one Voigt component of a held scene (every other stress held), with the
// engine chain of a study; returns the modulus. Tight settings as the probe-versus-static tests.
Real dynamicProbe(const std::shared_ptr<Scene>& s, int axis, int sign) {
  auto probe = std::make_shared<StressProbe>();
  probe->axis = axis;
  probe->sign = sign;
  probe->law = CellServoLaw{0.01, 10.0};
  probe->rampSteps = 2000;
  probe->settleSteps = 200;
  probe->relativeTolerance = 1e-4;
  probe->unbalancedTolerance = 1e-7;
  Simulation sim(s);
  sim.add(std::make_shared<ContactDetection>());
  sim.add(std::make_shared<ContactForces>());
  sim.add(probe);
  auto stepper = std::make_shared<TimeStepper>();
  stepper->maxDt = 1e-7;
  sim.add(stepper);
  auto newton = std::make_shared<NewtonIntegrator>();
  newton->damping = 0.4;
  sim.add(newton);
  refreshContacts(*s);
  s->dt = 0.5 * TimeStepper::stiffnessBound(*s);
  probe->start(*s, voigt::fromTensor(loveWeberStress(*s)));
  sim.run(200000);
  EXPECT_EQ(probe->stage, StressProbe::Stage::Done) << probe->message << " steps " << probe->steps << " unbalanced " << probe->unbalanced << " stress " << probe->stress.transpose();
  const Real G = probe->modulus();
  probe->restore(*s);
  return G;
}

}  // namespace

// The dynamic shear probes of the FCC lattice (orthorhombic cell of 2^3 conventional cells, which
// the probe then shears): G_yz, G_xz, G_xy against the closed-form C_44 of the same lattice, the
// prestress terms included. A shear of gamma = 1e-6 changes no normal force to first order, so the
// secant is the tangent to O(gamma^2); measured: each probe within 4e-9 of C_44 (the equilibrium
// tolerance, unbalanced force 1e-7), so 1e-6 is asserted, on each sign and on the +/- mean.
TEST(ShearedCell, FaceCentredCubicShearProbeGivesC44) {
  const Real delta = 4e-7;
  auto s = fcc(2, delta);
  const Real C44 = fccStiffness(s->material, delta)(3, 3);
  for (int axis = 3; axis < 6; ++axis) {
    const Real up = dynamicProbe(s, axis, 1), down = dynamicProbe(s, axis, -1);
    EXPECT_NEAR(up / C44, 1.0, 1e-6) << "axis " << axis;
    EXPECT_NEAR(down / C44, 1.0, 1e-6) << "axis " << axis;
    EXPECT_NEAR(0.5 * (up + down) / C44, 1.0, 1e-6) << "axis " << axis;
    EXPECT_TRUE(s->cell.orthorhombic());  // restored
  }
}
