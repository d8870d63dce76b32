// Clump templates (CGAL union of balls) against closed forms and a column integration; bad input;
// the scene's solid volume and void ratio; free rotation of an asymmetric clump.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "Drivers.hpp"
#include "UnionReference.hpp"
#include "clump/ClumpTemplate.hpp"
#include "clump/UnionOfBalls.hpp"
#include "dynamics/HalfAngle.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "measure/Coordination.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

constexpr Real kPi = 3.14159265358979323846;

Mat3 inertiaTensor(const ClumpTemplate& t) { return t.axes * t.inertia.asDiagonal() * t.axes.transpose(); }

// Relative errors of a template against reference moments: volume, centroid (in units of the
// equivalent radius) and inertia tensor (Frobenius, which also tests the principal axes).
struct Errors {
  Real volume, centroid, inertia;
};
Errors compare(const ClumpTemplate& t, const Moments& ref) {
  const Real req = std::cbrt(3 * ref.V / (4 * kPi));
  const Mat3 Iref = ref.inertia();
  return {std::abs(t.volume / ref.V - 1), (t.centroid - ref.centroid()).norm() / req,
          (inertiaTensor(t) - Iref).norm() / Iref.norm()};
}

// Members of the three- and four-ball test clumps (no symmetry: every axis is a test).
std::vector<Vec3> trimerCentres() { return {Vec3(0, 0, 0), Vec3(0.7, 0.1, 0.05), Vec3(1.2, 0.6, 0.2)}; }
std::vector<Real> trimerRadii() { return {1.0, 0.8, 0.6}; }
std::vector<Vec3> tetramerCentres() {
  return {Vec3(0, 0, 0), Vec3(0.9, 0, 0.1), Vec3(0.45, 0.78, 0), Vec3(0.45, 0.26, 0.73)};
}
std::vector<Real> tetramerRadii() { return {0.6, 0.55, 0.65, 0.5}; }

}  // namespace

// The CGAL volume of two overlapping balls against the closed-form lens, V1 + V2 - lens, over
// overlaps from a thin neck (0.5 % of the radius) to a ball nearly inside the other, and the first
// and second moments against the closed-form solid of revolution. Measured with the Richardson-
// extrapolated level-4 mesh: volume 4e-8..8.8e-6, 2.8e-5 for the thin neck; centroid <= 2.1e-6 of
// r_eq; inertia tensor <= 1.8e-5. Tolerance 5e-5: still below what a void ratio to 1e-4 needs
// (de = (1+e) dV/V, so dV/V < 6e-5 at e = 0.6).
TEST(UnionOfBalls, TwoBallsMatchClosedFormLens) {
  struct Case { Real R, r, d; };
  for (const Case& c : {Case{1, 1, 1.0}, Case{1, 1, 1.99}, Case{1, 1, 0.3}, Case{1, 0.5, 1.2},
                        Case{1, 0.6, 0.5}, Case{2e-4, 1e-4, 2.2e-4}}) {
    SCOPED_TRACE(::testing::Message() << "R " << c.R << " r " << c.r << " d " << c.d);
    const Real h1 = (c.r - c.R + c.d) * (c.r + c.R - c.d) / (2 * c.d);  // lens = two caps
    const Real h2 = (c.R - c.r + c.d) * (c.r + c.R - c.d) / (2 * c.d);
    const Real lens = kPi / 3 * (h1 * h1 * (3 * c.R - h1) + h2 * h2 * (3 * c.r - h2));
    const Real exact = 4.0 / 3.0 * kPi * (c.R * c.R * c.R + c.r * c.r * c.r) - lens;
    const ClumpTemplate t = makeClumpTemplate({Vec3::Zero(), Vec3(c.d, 0, 0)}, {c.R, c.r});
    EXPECT_NEAR(t.volume / exact, 1.0, 5e-5);
    const Moments ref = twoBallsClosedForm(c.R, c.r, c.d);
    EXPECT_NEAR(ref.V / exact, 1.0, 1e-12);  // the two closed forms agree
    const Errors e = compare(t, ref);
    EXPECT_LT(e.centroid, 1e-5);
    EXPECT_LT(e.inertia, 5e-5);
    EXPECT_LT(t.volumeErrorEstimate, 2e-4);  // the estimate bounds the true error from above
    EXPECT_GT(t.volumeErrorEstimate, std::abs(t.volume / exact - 1));
  }
}

// A ball inside another adds nothing: the union is the large ball, exactly in closed form.
TEST(UnionOfBalls, ContainedBallAddsNothing) {
  const ClumpTemplate t = makeClumpTemplate({Vec3::Zero(), Vec3(0.3, 0, 0)}, {1.0, 0.5});
  EXPECT_NEAR(t.volume / (4.0 / 3.0 * kPi), 1.0, 5e-5);
  EXPECT_NEAR(t.inertia.x() / (0.4 * 4.0 / 3.0 * kPi), 1.0, 5e-5);
}

// Asymmetric three- and four-member clumps against the column integration at n = 1000 (its own
// error, from the change at n = 2000: 1.5e-6 of V, 3e-6 of I). Template errors measured against
// n = 2000: V 5.1e-6 / 2.1e-6, centroid 2.2e-6 / 2.8e-7 of r_eq, inertia 1.1e-5 / 5.1e-6
// (trimer / tetramer); tolerances as above.
TEST(ClumpTemplate, AsymmetricClumpsMatchColumnIntegration) {
  for (int shape = 0; shape < 2; ++shape) {
    SCOPED_TRACE(shape ? "tetramer" : "trimer");
    const auto c = shape ? tetramerCentres() : trimerCentres();
    const auto r = shape ? tetramerRadii() : trimerRadii();
    const ClumpTemplate t = makeClumpTemplate(c, r);
    const Errors e = compare(t, columnIntegration(c, r, 1000));
    EXPECT_LT(e.volume, 5e-5);
    EXPECT_LT(e.centroid, 1e-5);
    EXPECT_LT(e.inertia, 5e-5);
    // Principal frame: ascending moments, a proper rotation, members placed back exactly.
    EXPECT_LT(t.inertia[0], t.inertia[1]);
    EXPECT_LT(t.inertia[1], t.inertia[2]);
    EXPECT_NEAR(t.axes.determinant(), 1.0, 1e-12);
    for (int k = 0; k < t.size(); ++k) EXPECT_LT((t.centroid + t.axes * t.offsets[k] - c[k]).norm(), 1e-12);
    // The template's own members, in its own frame: centroid at 0, inertia diagonal, to the
    // method's accuracy (the mesh of a turned member set is another mesh: 1.6e-6 and 4e-6 of I
    // measured).
    const ClumpTemplate again = makeClumpTemplate(t.offsets, t.radii);
    EXPECT_LT(again.centroid.norm(), 1e-5);
    EXPECT_LT((inertiaTensor(again) - Mat3(t.inertia.asDiagonal())).norm(), 5e-5 * t.inertia.norm());
  }
}

// Scaling: lengths f, volume f^3, moments f^5 (and the cache keys scale and rigid motion away).
TEST(ClumpTemplate, ScalesAndCachesPerShape) {
  const ClumpTemplate t = makeClumpTemplate(trimerCentres(), trimerRadii());
  const Real f = 1.7e-4;
  const ClumpTemplate s = t.scaled(f);
  EXPECT_NEAR(s.volume / (t.volume * f * f * f), 1.0, 1e-14);
  EXPECT_NEAR(s.inertia.norm() / (t.inertia.norm() * std::pow(f, 5)), 1.0, 1e-14);
  EXPECT_NEAR(s.equivalentDiameter() / (f * t.equivalentDiameter()), 1.0, 1e-14);
  // A rotated, shifted, scaled and re-ordered copy has the same shape: one volume, scaled.
  const Mat3 R = Eigen::AngleAxisd(0.8, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Vec3> moved;
  std::vector<Real> radii;
  for (int k : {2, 0, 1}) {
    moved.push_back(Vec3(1, -2, 0.5) + f * (R * trimerCentres()[k]));
    radii.push_back(f * trimerRadii()[k]);
  }
  // (Another frame is another mesh: the two agree to the method's accuracy.)
  const Real v = cachedClumpVolume(moved, radii);
  EXPECT_NEAR(v / s.volume, 1.0, 2e-5);
  EXPECT_NEAR(cachedClumpVolume(trimerCentres(), trimerRadii()) / t.volume, 1.0, 2e-5);
  EXPECT_NEAR(cachedClumpVolume(trimerCentres(), trimerRadii()) * f * f * f / v, 1.0, 1e-13);  // one entry
}

// Bad input gets one clear error before any geometry is computed, and a scene is left unchanged.
TEST(ClumpTemplate, RejectsBadMembers) {
  const Real nan = std::nan("");
  auto rejects = [](std::vector<Vec3> c, std::vector<Real> r, const std::string& words) {
    try {
      makeClumpTemplate(c, r);
      ADD_FAILURE() << "accepted: " << words;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  rejects({Vec3::Zero(), Vec3(1, 0, 0)}, {1.0, 0.0}, "radius must be a finite number > 0");
  rejects({Vec3::Zero(), Vec3(1, 0, 0)}, {-1.0, 1.0}, "radius must be a finite number > 0");
  rejects({Vec3::Zero(), Vec3(1, 0, 0)}, {1.0, nan}, "radius must be a finite number > 0");
  rejects({Vec3::Zero(), Vec3(nan, 0, 0)}, {1.0, 1.0}, "centre must be finite");
  rejects({Vec3::Zero(), Vec3(3, 0, 0)}, {1.0, 1.0}, "do not form one body");
  rejects({Vec3::Zero(), Vec3(2, 0, 0)}, {1.0, 1.0}, "do not form one body");  // touching at a point
  rejects({Vec3::Zero(), Vec3(1, 0, 0), Vec3(5, 0, 0), Vec3(6, 0, 0)}, {1, 1, 1, 1}, "do not form one body");
  rejects({}, {}, "at least one member");
  rejects({Vec3::Zero()}, {1.0, 1.0}, "as many member centres as radii");

  Scene s;
  s.material = paperMaterial();
  s.cell.setBox(Vec3::Constant(1e-2));
  EXPECT_THROW(s.addClump(Vec3::Zero(), Quat::Identity(), {Vec3::Zero(), Vec3(3e-4, 0, 0)}, {1e-4, 1e-4}, 1e-9,
                          Vec3::Constant(1e-17)),
               InputError);
  EXPECT_THROW(s.addClump(Vec3::Zero(), Quat::Identity(), {Vec3::Zero(), Vec3(1e-4, 0, 0)}, {1e-4, 1e-4}, nan,
                          Vec3::Constant(1e-17)),
               InputError);
  EXPECT_EQ(s.bodies.size(), 0);
  EXPECT_EQ(s.members.size(), 0);
}

// The void ratio counts a clump's overlap once: a cell holding one dimer of two unit-size balls at
// distance r has e = V_cell / V_union - 1, not V_cell / (2 V_ball) - 1 (that would be 6.7 % off here).
TEST(ClumpTemplate, VoidRatioUsesUnionVolume) {
  const Real r = 1e-4;
  const ClumpTemplate t = makeClumpTemplate({Vec3::Zero(), Vec3(r, 0, 0)}, {r, r});
  Scene s;
  s.material = paperMaterial();
  s.cell.setBox(Vec3::Constant(10 * r));
  s.addClump(Vec3::Constant(5 * r), Quat::Identity(), t);
  const Real lens = 5.0 / 12.0 * kPi * r * r * r;  // two caps of height r/2
  const Real union_ = 8.0 / 3.0 * kPi * r * r * r - lens;
  EXPECT_NEAR(solidVolume(s) / union_, 1.0, 5e-5);
  EXPECT_NEAR(voidRatio(s), s.cell.volume() / union_ - 1.0, 5e-5 * s.cell.volume() / union_);
  EXPECT_NEAR(s.bodies.mass[0] / (s.material.density * union_), 1.0, 5e-5);
  // The file/YADE path (offsets, mass, inertia given) gets the same volume from the cache.
  s.addClump(Vec3::Constant(2 * r), Quat::Identity(), t.offsets, t.radii, 1e-9, Vec3::Constant(1e-17));
  EXPECT_NEAR(s.bodies.volume[1] / s.bodies.volume[0], 1.0, 2e-5);
  // A saved scene's own volume is taken as given, bit for bit (the cache's last bits depend on the
  // clump it met first); a negative or NaN one is refused, and the members are still checked.
  const Real saved = std::nextafter(s.bodies.volume[0], 1.0);
  s.addClump(Vec3::Constant(8 * r), Quat::Identity(), t.offsets, t.radii, 1e-9, Vec3::Constant(1e-17), saved);
  EXPECT_EQ(s.bodies.volume[2], saved);
  EXPECT_THROW(s.addClump(Vec3::Zero(), Quat::Identity(), t.offsets, t.radii, 1e-9, Vec3::Constant(1e-17), -saved),
               InputError);
  EXPECT_THROW(s.addClump(Vec3::Zero(), Quat::Identity(), t.offsets, t.radii, 1e-9, Vec3::Constant(1e-17),
                          std::nan("")),
               InputError);
  EXPECT_THROW(s.addClump(Vec3::Zero(), Quat::Identity(), {Vec3::Zero(), Vec3(3 * r, 0, 0)}, {r, r}, 1e-9,
                          Vec3::Constant(1e-17), saved),
               InputError);
  EXPECT_EQ(s.bodies.size(), 3);
}

// Torque-free rotation of an asymmetric clump (damping off): the angular momentum in the world
// frame is conserved to round-off and the kinetic energy oscillates without drift. The clump spins
// near its intermediate axis (the unstable one, where an integrator's errors show first) at
// |w| dt = 0.01 rad per step, 1e5 steps (160 turns). Measured: |L - L0|/|L0| = 3.9e-11 (4e-16 per
// step: the same rounding repeats at every step of a steady spin), energy within 1.9e-6 of its
// start, and the mean of the last tenth within 2e-8 of the first tenth's. The explicit update of
// Euler's equations used before this splitting gave 2.1e-2, 4.3e-2 and 3.8e-2 on the same run.
TEST(NewtonIntegrator, FreeAsymmetricClumpConservesMomentumAndEnergy) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real f = 1e-4;
  std::vector<Vec3> c;
  std::vector<Real> r;
  for (const Vec3& x : trimerCentres()) c.push_back(f * x);
  for (Real x : trimerRadii()) r.push_back(f * x);
  const ClumpTemplate t = makeClumpTemplate(c, r);
  s->cell.setBox(Vec3::Constant(20 * f));
  const int b = s->addClump(Vec3::Constant(10 * f), Quat(Eigen::AngleAxisd(0.3, Vec3(1, 1, 0).normalized())), t);
  const Quat q = s->bodies.orientation[b];
  const Vec3 wBody(0.05, 1.0, 0.03);
  s->dt = 1e-6;
  s->bodies.angVel[b] = q * (wBody * (0.01 / s->dt / wBody.norm()));
  Simulation sim(s);
  auto newton = std::make_shared<NewtonIntegrator>();
  newton->damping = 0;
  sim.add(newton);
  auto momentum = [&] {
    const Quat& o = s->bodies.orientation[b];
    return Vec3(o * s->bodies.inertia[b].cwiseProduct(o.conjugate() * s->bodies.angVel[b]));
  };
  auto energy = [&] {
    const Vec3 w = s->bodies.orientation[b].conjugate() * s->bodies.angVel[b];
    return 0.5 * w.dot(s->bodies.inertia[b].cwiseProduct(w));
  };
  const Vec3 L0 = momentum();
  const Real E0 = energy();
  const int steps = 100000, tenth = steps / 10;
  Real first = 0, last = 0, worst = 0;
  for (int k = 0; k < steps; ++k) {
    sim.run(1);
    const Real e = energy() / E0 - 1;
    worst = std::max(worst, std::abs(e));
    if (k < tenth) first += e / tenth;
    if (k >= steps - tenth) last += e / tenth;
  }
  const Quat turned = s->bodies.orientation[b];
  EXPECT_GT(q.angularDistance(turned), 0.1);  // it did turn
  EXPECT_LT((momentum() - L0).norm() / L0.norm(), 1e-9);
  EXPECT_LT(worst, 2e-5);
  EXPECT_LT(std::abs(last - first), 1e-6);
  RecordProperty("momentum_drift", std::to_string((momentum() - L0).norm() / L0.norm()));
  RecordProperty("energy_max", std::to_string(worst));
  RecordProperty("energy_drift", std::to_string(last - first));
  std::printf("free clump, 1e5 steps: |dL|/L = %.2e, max |dE|/E = %.2e, drift of the mean %.2e\n",
              (momentum() - L0).norm() / L0.norm(), worst, last - first);
}

// The integrator rotates clumps side by side, four at a time (NewtonIntegrator::advanceClumps).
// Seven free clumps of two shapes, with spheres between them, each with its own orientation, spin
// and torque-free motion, stepped together must end in the bits each ends in when stepped alone in
// a scene of its own: a clump's sub-steps may not read another's orientation, momentum or inertia,
// and the three left after the first four, and the spheres among them, go through the same code.
TEST(NewtonIntegrator, ClumpsSideBySideGiveTheBitsOfEachAlone) {
  const Real f = 1e-4;
  std::vector<ClumpTemplate> shapes;
  for (int k = 0; k < 2; ++k) {
    std::vector<Vec3> c;
    std::vector<Real> r;
    for (const Vec3& x : k ? tetramerCentres() : trimerCentres()) c.push_back(f * x);
    for (Real x : k ? tetramerRadii() : trimerRadii()) r.push_back(f * x);
    shapes.push_back(makeClumpTemplate(c, r));
  }
  const int n = 9;  // seven clumps, and spheres at 2 and 5
  auto place = [&](Scene& s, int k) {
    const Vec3 at = Vec3(4 * k + 2, 10, 10) * f;
    if (k == 2 || k == 5) {
      const int b = s.addSphere(at, 0.7 * f);
      s.bodies.angVel[b] = Vec3(1e3 * k, -2e3, 5e2);
      return;
    }
    const Quat q(Eigen::AngleAxisd(0.3 + 0.4 * k, Vec3(1, k, 2).normalized()));
    const int b = s.addClump(at, q, shapes[k % 2]);
    s.bodies.angVel[b] = q * Vec3(0.05 * k, 1.0, 0.03 + 0.01 * k) * (1e4 / (1 + k));
  };
  auto stepped = [&](const std::vector<int>& which) {
    auto s = std::make_shared<Scene>();
    s->material = paperMaterial();
    s->cell.setBox(Vec3(4 * n + 4, 20, 20) * f);
    for (int k : which) place(*s, k);
    s->dt = 1e-7;
    Simulation sim(s);
    auto newton = std::make_shared<NewtonIntegrator>();
    newton->damping = 0.2;  // the damped rotation too (zero torque: it leaves the spin as it is)
    sim.add(newton);
    sim.run(500);
    return s;
  };
  std::vector<int> all(n);
  for (int k = 0; k < n; ++k) all[k] = k;
  const auto together = stepped(all);
  for (int k = 0; k < n; ++k) {
    const auto alone = stepped({k});
    EXPECT_EQ(together->bodies.orientation[k].coeffs(), alone->bodies.orientation[0].coeffs()) << "body " << k;
    EXPECT_EQ(together->bodies.angVel[k], alone->bodies.angVel[0]) << "body " << k;
  }
  EXPECT_GT(together->bodies.orientation[3].angularDistance(Quat(Eigen::AngleAxisd(1.5, Vec3(1, 3, 2).normalized()))),
            0.05);  // it turned
}

// Members of one clump overlap by construction but never touch each other: detection lists no
// pair inside a body, so nothing there carries a force or counts in Nc (fabric, Zm, stress).
TEST(ClumpTemplate, MembersOfOneClumpAreNotContacts) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real r = 1e-4;
  const ClumpTemplate t = makeClumpTemplate({Vec3::Zero(), Vec3(r, 0, 0), Vec3(0.5 * r, 0.8 * r, 0)}, {r, r, r});
  s->cell.setBox(Vec3::Constant(10 * r));
  s->addClump(Vec3::Constant(5 * r), Quat::Identity(), t);
  s->addClump(Vec3::Constant(5 * r) + Vec3(0, 0, 2 * t.boundingRadius() + r), Quat::Identity(), t);  // apart
  s->dt = 1e-9;
  ContactDetection detection;
  detection.apply(*s);
  ContactForces forces;
  forces.apply(*s);
  EXPECT_EQ(s->contacts.size(), 0);
  EXPECT_EQ(coordination(*s).contacts, 0);
  EXPECT_EQ(s->bodies.force[0], Vec3::Zero());
  EXPECT_EQ(s->bodies.torque[0], Vec3::Zero());
}

// The rotation's small-angle branch gives the bits of the library's cos and sin: below 2^-27 cos
// rounds to 1 and sin to the angle (the next terms of their series are below half an ulp). A
// threshold set too high (2^-26 already) would give cos 1 where it is 1 - 2^-53.
TEST(ClumpRotation, SmallHalfAnglesGiveTheLibrarysCosAndSin) {
  const auto same = [](Real v) {
    Real c, s;
    halfAngleCosSin(v, c, s);
    return c == std::cos(v) && s == std::sin(v);
  };
  int checked = 0;
  for (Real x = 1e-300; x < 1e-6; x *= 1.01, checked += 2) {
    ASSERT_TRUE(same(x)) << x;
    ASSERT_TRUE(same(-x)) << x;
  }
  EXPECT_GT(checked, 100000);
  for (Real v : {std::nextafter(Real(0x1p-27), 0.0), Real(0x1p-27), Real(0.0)}) {
    EXPECT_TRUE(same(v)) << v;
    EXPECT_TRUE(same(-v)) << v;
  }
  EXPECT_NE(std::cos(Real(0x1p-26)), 1.0);  // why the branch stops at 2^-27
}
