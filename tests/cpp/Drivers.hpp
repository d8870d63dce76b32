#pragma once
// Reusable contact-law drivers for the tests (in the manner of MercuryDPM's unit tests): small
// scenes whose kinematics the test prescribes, with only detection and forces running.
#include <memory>

#include "core/Scene.hpp"
#include "dynamics/ContactDetection.hpp"
#include "dynamics/ContactForces.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"

namespace trueaniso::testing {

inline Material paperMaterial(Real mu = 0.5) {
  Material m;
  m.shearModulus = 18e9;
  m.poisson = 0.15;
  m.density = 2500;
  m.friction = mu;
  return m;
}

// Two spheres on the x axis in a big periodic box, sphere 0 at the box centre.
inline std::shared_ptr<Scene> twoSpheres(Real r1, Real r2, Real delta, Real mu = 0.5) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial(mu);
  const Real box = 10.0 * (r1 + r2);
  s->cell.setBox(Vec3::Constant(box));
  const Vec3 c = Vec3::Constant(0.5 * box);
  s->addSphere(c, r1);
  s->addSphere(c + Vec3(r1 + r2 - delta, 0, 0), r2);
  s->dt = 1e-8;
  return s;
}

// Evaluates forces at the current kinematics, then advances positions by their velocities
// (leap-frog order: the force at x_k uses the velocity that brought the bodies to x_k).
class Driver {
 public:
  explicit Driver(std::shared_ptr<Scene> s) : s_(std::move(s)) { detection_.skinFactor = 0.5; }
  void evaluate() {
    s_->members.pos = s_->bodies.pos;
    detection_.apply(*s_);
    forces_.apply(*s_);
  }
  void move() {
    for (int b = 0; b < s_->bodies.size(); ++b) s_->bodies.pos[b] += s_->dt * s_->bodies.vel[b];
    s_->members.pos = s_->bodies.pos;
    s_->time += s_->dt;
    ++s_->step;
  }
  Scene& scene() { return *s_; }
  ContactDetection& detection() { return detection_; }

 private:
  std::shared_ptr<Scene> s_;
  ContactDetection detection_;
  ContactForces forces_;
};

// A rigid rotation of a two-body scene about its mid-point at angular velocity Omega: place(k)
// sets the positions after k steps, the velocities of the rigid motion at the same instant (so
// the contact point's relative velocity is zero and only the frame rotation acts on the
// contact's history) and both spins to Omega; returns the rotation.
class RigidRotation {
 public:
  RigidRotation(Scene& s, const Vec3& Omega)
      : s_(s), Omega_(Omega), centre_(0.5 * (s.bodies.pos[0] + s.bodies.pos[1])),
        x0_(s.bodies.pos[0] - centre_), x1_(s.bodies.pos[1] - centre_) {}
  Eigen::AngleAxisd place(int k) {
    const Eigen::AngleAxisd R(Omega_.norm() * s_.dt * k, Omega_.normalized());
    s_.bodies.pos[0] = centre_ + R * x0_;
    s_.bodies.pos[1] = centre_ + R * x1_;
    s_.bodies.vel[0] = Omega_.cross(R * x0_);
    s_.bodies.vel[1] = Omega_.cross(R * x1_);
    s_.bodies.angVel[0] = s_.bodies.angVel[1] = Omega_;
    return R;
  }

 private:
  Scene& s_;
  Vec3 Omega_, centre_, x0_, x1_;
};

// Spins body 1 at w for `steps` evaluations (positions fixed), then stops it.
inline void spinBody1(Driver& drv, const Vec3& w, int steps) {
  drv.scene().bodies.angVel[1] = w;
  for (int k = 0; k < steps; ++k) drv.evaluate();
  drv.scene().bodies.angVel[1].setZero();
}

// The stepper's chain as dem.Chain builds it in Python: detection, forces, a damped integrator.
inline Simulation steppingChain(std::shared_ptr<Scene> s, Real damping) {
  Simulation sim(std::move(s));
  sim.add(std::make_shared<ContactDetection>());
  sim.add(std::make_shared<ContactForces>());
  auto newton = std::make_shared<NewtonIntegrator>();
  newton->damping = damping;
  sim.add(newton);
  return sim;
}

}  // namespace trueaniso::testing
