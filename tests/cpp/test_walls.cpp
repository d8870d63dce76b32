// Rigid frictionless walls (boundary/RigidWalls.hpp): the wall contact law against the closed form
// of a sphere on a rigid half-space, no force without contact, a refused setup, and the wall servo
// holding a simple cubic lattice at its goal stress against the lattice's closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "Drivers.hpp"
#include "boundary/RigidWalls.hpp"

namespace trueaniso::testing {
namespace {

constexpr Real kRadius = 1e-4;

// Hertz of a sphere (E, nu) on a rigid half-space from Young's modulus: 1/E* = (1 - nu^2)/E,
// N = (4/3) E* sqrt(R) delta^(3/2) (Johnson, Contact Mechanics, Eq. 4.22 with R = r).
Real hertzOnRigidPlane(const Material& m, Real r, Real delta) {
  const Real E = 2.0 * m.shearModulus * (1.0 + m.poisson);
  const Real Estar = E / (1.0 - m.poisson * m.poisson);
  return 4.0 / 3.0 * Estar * std::sqrt(r) * std::pow(delta, 1.5);
}
// The same for two equal spheres: 1/E* = 2 (1 - nu^2)/E, R* = r/2.
Real hertzTwoSpheres(const Material& m, Real r, Real delta) {
  const Real E = 2.0 * m.shearModulus * (1.0 + m.poisson);
  const Real Estar = E / (2.0 * (1.0 - m.poisson * m.poisson));
  return 4.0 / 3.0 * Estar * std::sqrt(0.5 * r) * std::pow(delta, 1.5);
}
// The overlap at which each law carries N (inverse of the two above).
Real overlapOf(Real N, Real unitForce) { return std::pow(N / unitForce, 2.0 / 3.0); }

// A cell of edge 14 r with walls around [4 r, 10 r]^3: 4 r of room on each side.
std::shared_ptr<Scene> walledScene() {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  s->cell.setBox(Vec3::Constant(14 * kRadius));
  return s;
}

TEST(RigidWalls, SphereOnWallIsHertzOnARigidPlane) {
  auto s = walledScene();
  RigidWalls w;
  w.setBox(Vec3::Constant(4 * kRadius), Vec3::Constant(10 * kRadius));
  // Sphere touching the lower x wall with overlap d1 and the upper z wall with overlap d2.
  const Real d1 = 1e-7, d2 = 3e-7;
  s->addSphere(Vec3(4 * kRadius + kRadius - d1, 7 * kRadius, 10 * kRadius - kRadius + d2), kRadius);
  s->bodies.resizeDynamics();
  s->dt = 1e-8;
  w.apply(*s);
  const Real N1 = hertzOnRigidPlane(s->material, kRadius, d1), N2 = hertzOnRigidPlane(s->material, kRadius, d2);
  // Tolerance 1e-12 relative: the same law by two algebraic routes (E* from G or from E), a few
  // roundings apart.
  EXPECT_NEAR(s->bodies.force[0].x(), N1, 1e-12 * N1);
  EXPECT_NEAR(s->bodies.force[0].z(), -N2, 1e-12 * N2);
  EXPECT_EQ(s->bodies.force[0].y(), 0.0);
  EXPECT_NEAR(w.force[0], N1, 1e-12 * N1);
  EXPECT_NEAR(w.force[5], N2, 1e-12 * N2);
  EXPECT_EQ(w.contacts[0], 1);
  EXPECT_EQ(w.contacts[5], 1);
  EXPECT_EQ(w.contacts[1] + w.contacts[2] + w.contacts[3] + w.contacts[4], 0);
  // k_n = dN/d delta, against a central difference of the closed form (truncation ~ (h/delta)^2 ~ 1e-8).
  const Real h = 1e-4 * d1;
  const Real kn = (hertzOnRigidPlane(s->material, kRadius, d1 + h) - hertzOnRigidPlane(s->material, kRadius, d1 - h)) / (2 * h);
  EXPECT_NEAR(w.stiffness[0], kn, 1e-6 * kn);
  // The wall stress is the mean of the pair's forces over their area.
  const Real A = 36 * kRadius * kRadius;
  EXPECT_NEAR(w.stress().x(), 0.5 * N1 / A, 1e-12 * N1 / A);
  // A wall contact is stiffer than a sphere pair's at the same overlap: 2 E* and R* = r, 2 sqrt(2) times.
  EXPECT_NEAR(N1 / hertzTwoSpheres(s->material, kRadius, d1), 2 * std::sqrt(2.0), 1e-12);
}

TEST(RigidWalls, NoForceWithoutContact) {
  auto s = walledScene();
  RigidWalls w;
  w.setBox(Vec3::Constant(4 * kRadius), Vec3::Constant(10 * kRadius));
  // Centre 1e-12 m farther than a radius from the nearest wall: no overlap, exactly zero force.
  s->addSphere(Vec3(5 * kRadius + 1e-12, 7 * kRadius, 7 * kRadius), kRadius);
  s->addSphere(Vec3(7 * kRadius, 7 * kRadius, 7 * kRadius), kRadius);
  s->bodies.resizeDynamics();
  s->dt = 1e-8;
  w.apply(*s);
  for (int b = 0; b < 2; ++b) EXPECT_EQ(s->bodies.force[b], Vec3::Zero());
  EXPECT_EQ(w.force, Vec6::Zero());
  EXPECT_EQ(w.contacts.sum(), 0);
  EXPECT_EQ(w.stress(), Vec3::Zero());
}

TEST(RigidWalls, RefusesABoxTooCloseToTheCellFace) {
  auto s = walledScene();
  s->addSphere(Vec3::Constant(7 * kRadius), kRadius);
  s->bodies.resizeDynamics();
  RigidWalls w;
  w.setBox(Vec3::Constant(4 * kRadius), Vec3::Constant(10 * kRadius));
  EXPECT_NO_THROW(w.validate(*s));
  // 8 r of the cell lie outside the box on each axis: a diameter (2 r) plus a margin must fit.
  w.margin = 2.5 * kRadius;
  EXPECT_NO_THROW(w.validate(*s));
  w.margin = 6.5 * kRadius;
  EXPECT_THROW(w.validate(*s), InputError);
  w.margin = 0;
  w.setBox(Vec3(4, 4, 4) * kRadius, Vec3(10, 13, 10) * kRadius);  // y box 9 r of a 14 r cell: 5 r left
  EXPECT_NO_THROW(w.validate(*s));
  w.setBox(Vec3(4, 4, 4) * kRadius, Vec3(10, 14.5, 10) * kRadius);  // beyond the cell
  EXPECT_THROW(w.validate(*s), InputError);
  w.setBox(Vec3::Constant(4 * kRadius), Vec3::Constant(10 * kRadius));
  s->cell.velGrad(0, 0) = 1.0;  // a moving cell: the walls load the specimen, not the cell
  EXPECT_THROW(w.validate(*s), InputError);
}

// A 3^3 simple cubic lattice between the walls, driven by the wall servo to an isotropic and to
// a true-triaxial state. Each axis carries n^2 columns of n spheres between its two walls, so
// N_k = sigma_k A_k / n^2 at every contact of the column and the gap is
// L_k = 2 n r - 2 delta_wall(N_k) - (n - 1) delta_pair(N_k), with A_k the product of the other two
// gaps (solved by fixed-point iteration; the overlaps are ~1e-4 of the gap, so it converges at once).
void expectLatticeHeldAt(const Vec3& goal, Real b, Real sigmaZ, Real p) {
  const int n = 3;
  auto s = walledScene();
  const Real lo = 4 * kRadius;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) s->addSphere(Vec3::Constant(lo) + 2 * kRadius * Vec3(i + 0.5, j + 0.5, k + 0.5), kRadius);
  s->bodies.resizeDynamics();
  s->dt = 2e-8;  // a tenth of sqrt(m / k_n) of the stiffest (wall) contact at 140 kPa
  auto walls = std::make_shared<RigidWalls>();
  walls->setBox(Vec3::Constant(lo), Vec3::Constant(lo + 2 * n * kRadius));
  walls->margin = kRadius;
  auto path = std::make_shared<TrueTriaxialServo>();
  path->goal = TrueTriaxialState{b, sigmaZ, p};
  path->controlShear = false;
  path->pathRate = 50.0;
  path->stressTolerance = 20.0;  // Pa: 2e-4 of the stress
  path->unbalancedTolerance = 1e-4;
  auto servo = std::make_shared<WallServo>(walls, path);
  auto detection = std::make_shared<ContactDetection>();
  auto integrator = std::make_shared<NewtonIntegrator>();
  integrator->damping = 0.4;
  Simulation sim(s);
  sim.add(detection);
  sim.add(std::make_shared<ContactForces>());
  sim.add(walls);
  sim.add(servo);
  sim.add(integrator);
  servo->start(*s);
  sim.run(2000000);
  ASSERT_EQ(path->status, TrueTriaxialServo::Status::Reached) << path->message;
  const Vec3 sig = walls->stress();
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(sig[k], goal[k], 20.0) << "axis " << k;

  Vec3 L = walls->width();
  for (int it = 0; it < 20; ++it) {
    Vec3 next;
    for (int k = 0; k < 3; ++k) {
      const Real A = L[(k + 1) % 3] * L[(k + 2) % 3];
      const Real N = goal[k] * A / (n * n);
      next[k] = 2 * n * kRadius - 2 * overlapOf(N, hertzOnRigidPlane(s->material, kRadius, 1.0)) -
                (n - 1) * overlapOf(N, hertzTwoSpheres(s->material, kRadius, 1.0));
    }
    L = next;
  }
  // Compared as compressions 2 n r - L: the stress is within 2e-4 of its goal, which moves an
  // overlap by 2/3 of that; 2e-3 leaves room for the residual motion at unbalanced force 1e-4.
  for (int k = 0; k < 3; ++k) {
    const Real expected = 2 * n * kRadius - L[k], got = 2 * n * kRadius - walls->width()[k];
    EXPECT_NEAR(got, expected, 2e-3 * expected) << "axis " << k;
  }
}

TEST(WallServo, HoldsALatticeAtAnIsotropicState) {
  expectLatticeHeldAt(Vec3::Constant(100e3), 0.0, 100e3, 100e3);
}

TEST(WallServo, HoldsALatticeAtATrueTriaxialState) {
  const TrueTriaxialState st{0.5, 140e3, 100e3};  // Table C1 state 21: (100, 60, 140) kPa
  expectLatticeHeldAt(st.stresses(), st.b, st.sigmaZ, st.p);
}

TEST(WallServo, RefusesShearControl) {
  auto s = walledScene();
  auto path = std::make_shared<TrueTriaxialServo>();  // controlShear on by default
  WallServo servo(std::make_shared<RigidWalls>(), path);
  EXPECT_THROW(servo.start(*s), InputError);
}

}  // namespace
}  // namespace trueaniso::testing
