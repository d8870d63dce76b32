#include "statics/HeldState.hpp"

#include <cmath>
#include <sstream>

#include "contact/HertzMindlin.hpp"
#include "dynamics/ContactRefresh.hpp"
#include "measure/Reduce.hpp"
#include "measure/Stress.hpp"

namespace trueaniso {

Scene heldState(const Scene& scene) {
  scene.validate();
  Scene held = scene;
  held.material.friction = kProbeFriction;  // the probes' value: nothing slides
  held.blockRotations = false;              // torques are wanted for the balance check
  refreshContacts(held);
  held.dt = 0;  // nothing of the held state moves
  return held;
}

Balance balance(const Scene& held) {
  Balance b;
  b.forces = unbalancedForce(held);
  b.torques = unbalancedTorque(held);
  return b;
}

void requireBalance(const Scene& held, Real limit, bool rotations) {
  const Balance b = balance(held);
  require(std::isfinite(b.forces), "no contact carries a force: a static stiffness needs a loaded network");
  std::ostringstream msg;
  if (!(b.forces <= limit)) {
    msg << "the state is out of force balance (unbalanced force " << b.forces << " > " << limit
        << "): relax it first; its tangent is not what a probe from it converges to";
    throw InputError(msg.str());
  }
  if (rotations && !(b.torques <= limit)) {
    msg << "the state is out of moment balance (unbalanced torque " << b.torques << " > " << limit
        << "): relax it first, or take the stiffness with rotations blocked";
    throw InputError(msg.str());
  }
}

HeldContact heldContact(const Scene& held, int c) {
  const Contacts& C = held.contacts;
  const Members& M = held.members;
  const Bodies& B = held.bodies;
  const int i = C.m1[c], j = C.m2[c];
  HeldContact h;
  h.normal = C.normal[c];
  h.shearForce = C.shearForce[c];
  h.branch = C.branch(c);
  h.offset1 = M.pos[i] - B.pos[C.b1[c]];
  h.offset2 = M.pos[j] - B.pos[C.b2[c]];
  h.normalForce = C.normalForce[c];
  const HertzMindlin law(held.material);
  h.kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
  h.ks = law.shearStiffness(h.kn);
  const Real delta = C.overlap[c];
  h.distance = M.radius[i] + M.radius[j] - delta;
  h.arm1 = M.radius[i] - 0.5 * delta;
  h.arm2 = M.radius[j] - 0.5 * delta;
  return h;
}

}  // namespace trueaniso
