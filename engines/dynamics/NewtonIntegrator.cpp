#include "dynamics/NewtonIntegrator.hpp"

#include <cmath>
#include <sstream>
#include <type_traits>

#include "core/Parallel.hpp"
#include "dynamics/HalfAngle.hpp"
#include "dynamics/TimeStepper.hpp"

namespace trueaniso {

namespace {

// YADE's cundallDamp2nd: the damping acts against the mid-step velocity of each component.
inline void dampLocal(Vec3& acc, const Vec3& vel, Real dt, Real damping) {
  for (int k = 0; k < 3; ++k) {
    const Real v = vel[k] + 0.5 * dt * acc[k];
    const Real s = acc[k] * v;
    acc[k] *= 1.0 - damping * ((s > 0) - (s < 0));
  }
}

// YADE's rule for aspherical bodies (cundallDamp1st): each torque component scaled by
// 1 - damping sign(T_k w_k), against the current angular velocity.
inline void dampTorque(Vec3& torque, const Vec3& angVel, Real damping) {
  for (int k = 0; k < 3; ++k) {
    const Real s = torque[k] * angVel[k];
    torque[k] *= 1.0 - damping * ((s > 0) - (s < 0));
  }
}

// Rotation of the body frame by `angle` about its own principal axis `axis` (the exact flow of the
// part L_axis^2 / (2 I_axis) of the kinetic energy): the orientation turns by +angle, the
// body-frame angular momentum by -angle, the world-frame one not at all.
// The axis is a template argument so that r is built in registers: set component by component
// (r.vec()[axis] = s), it went through memory as two 8-byte stores that the quaternion product
// then read back as one 16-byte load, which the processor cannot forward from them (a stall of
// ~15 % of the clump rotation, perf). The same values, so the same bits.
template <int Axis>
inline void turnAboutAxis(Quat& q, Vec3& Lbody, Real angle) {
  const Real half = 0.5 * angle;
  Real c, s;
  halfAngleCosSin(half, c, s);
#if defined(__GNUC__) && defined(__SSE2__)
  // GCC computes both with one sincos call that stores them to memory; read back as one pair,
  // they stalled like r did. Each taken into its own register first: the same values.
  asm("" : "+x"(c));
  asm("" : "+x"(s));
#endif
  const Quat r(c, Axis == 0 ? s : 0.0, Axis == 1 ? s : 0.0, Axis == 2 ? s : 0.0);
  q = q * r;
  Lbody = r.conjugate() * Lbody;
}

}  // namespace

// A rigid clump with anisotropic inertia. The angular momentum L (world frame) is advanced by the
// torque, L += dt T; the orientation then follows the torque-free motion at that L over dt, split
// into exact rotations about the principal axes, 1 (dt/2) 2 (dt/2) 3 (dt) 2 (dt/2) 1 (dt/2)
// (the symmetric splitting of Dullweber, Leimkuhler & McLachlan, J. Chem. Phys. 107 (1997) 5840).
// Each sub-step keeps L exactly, so a clump without torque conserves its angular momentum to
// round-off; the splitting is symplectic and time-reversible, so the kinetic energy oscillates by
// O(dt^2) without drift (tests/cpp/test_clump.cpp measures both). L is not stored: it is rebuilt
// from the stored angular velocity, which is set from L at the new orientation, w = R I^-1 R^T L.
//
// `count` (<= kClumpLanes) clumps at a time, each sub-step done for all of them before the next:
// one clump is a single chain of about 500 dependent operations (five sines and cosines among
// them), longer than the processor looks ahead, so clump after clump would leave it waiting; side
// by side their chains overlap. Every clump does the operations it would do alone, in its order: the same bits.
void NewtonIntegrator::advanceClumps(Bodies& B, const int* bodies, int count, Real dt, Real damping) {
  Quat q[kClumpLanes];
  Vec3 Lbody[kClumpLanes], I[kClumpLanes];
  for (int l = 0; l < count; ++l) {
    const int b = bodies[l];
    q[l] = B.orientation[b];
    I[l] = B.inertia[b];
    Vec3 torque = B.torque[b];
    if (damping != 0) dampTorque(torque, B.angVel[b], damping);
    const Vec3 L = q[l] * I[l].cwiseProduct(q[l].conjugate() * B.angVel[b]) + dt * torque;
    Lbody[l] = q[l].conjugate() * L;
  }
  const auto turn = [&](auto axis, Real share) {  // axis: std::integral_constant
    for (int l = 0; l < count; ++l)
      turnAboutAxis<axis()>(q[l], Lbody[l], share * dt * Lbody[l][axis()] / I[l][axis()]);
  };
  turn(std::integral_constant<int, 0>(), 0.5);
  turn(std::integral_constant<int, 1>(), 0.5);
  turn(std::integral_constant<int, 2>(), 1.0);
  turn(std::integral_constant<int, 1>(), 0.5);
  turn(std::integral_constant<int, 0>(), 0.5);
  for (int l = 0; l < count; ++l) {
    const int b = bodies[l];
    q[l].normalize();
    B.orientation[b] = q[l];
    B.angVel[b] = q[l] * Lbody[l].cwiseQuotient(I[l]);
  }
}

template <bool Rotations, bool Clumps>
void NewtonIntegrator::integrate(Scene& s) const {
  Bodies& B = s.bodies;
  const Real dt = s.dt;
  // The affine map of the step, x -> (I + dt L) x: axis by axis for an orthorhombic cell.
  const bool sheared = !s.cell.orthorhombic();
  const Mat3 map = Mat3::Identity() + dt * s.cell.velGrad;
  const Vec3 stretch = map.diagonal();
  const int nb = B.size();
  const Real damp = damping;
  // Single spheres: each member position is its body's, copied where the body moves, on the team
  // (a copy of the whole array after the loop was serial work the second thread waited through).
  Vec3* const memberPos = !Clumps && s.members.size() == nb ? s.members.pos.data() : nullptr;
#pragma omp parallel if (worthThreadsBeside(nb, s.contacts.size()))
  {
    int waiting[kClumpLanes];  // this thread's clumps whose rotation is still to do
    int nw = 0;
#pragma omp for schedule(static) nowait
    for (int b = 0; b < nb; ++b) {
      Vec3 acc = B.force[b] / B.mass[b];
      if (damp != 0) dampLocal(acc, B.vel[b], dt, damp);
      B.vel[b] += dt * acc;
      B.pos[b] = (sheared ? Vec3(map * B.pos[b]) : Vec3(B.pos[b].cwiseProduct(stretch))) + dt * B.vel[b];
      if (!Clumps && memberPos) memberPos[b] = B.pos[b];
      if (!Rotations) continue;
      if (!Clumps || B.memberCount(b) == 1) {
        // A sphere's inertia is isotropic: no orientation to track, nothing reads it.
        Vec3 angAcc = B.torque[b] / B.inertia[b].x();
        if (damp != 0) dampLocal(angAcc, B.angVel[b], dt, damp);
        B.angVel[b] += dt * angAcc;
      } else {
        waiting[nw++] = b;
        if (nw == kClumpLanes) {
          advanceClumps(B, waiting, nw, dt, damp);
          nw = 0;
        }
      }
    }
    if (nw > 0) advanceClumps(B, waiting, nw, dt, damp);
  }
  s.cell.hSize = sheared ? Mat3(map * s.cell.hSize) : Mat3(stretch.asDiagonal() * s.cell.hSize);
  if (Clumps) s.refreshMembers();
  else if (!memberPos) s.members.pos = B.pos;  // kept equal for engines that read member positions
}

// A time stepper below its cap changes the step every tenth step (clumps under the smallest-inertia
// rule, a preparation's default), and the walk over the contacts (a 3 x 3 eigenvalue a clump
// contact) costs 1.3-1.7 steps of a clump packing timed alone: a check at each change would be
// 5.6 % of the instructions of a clump2 chain and about 10 % of perf's samples of a clump1
// preparation. A step at most half the last limit found is checked on the regular interval only:
// the stiffest contact would have to stiffen fourfold (a Hertz contact's overlap sixteenfold)
// within it to reach the step. A time stepper's step lies at 0.24-0.34 of the limit in packed specimens (per-axis;
// smallest-inertia 0.08-0.20); a packing's loosest states bring it nearer, and each change is
// checked again there.
void NewtonIntegrator::checkStability(const Scene& s) {
  const bool recent = s.step >= checkedStep_ && s.step - checkedStep_ < checkEvery;
  if (recent && s.dt <= 0.5 * checkedLimit_) return;
  const Real limit = TimeStepper::criticalPairStep(s);
  if (s.dt >= limit) {
    std::ostringstream msg;
    msg << "unstable time step refused: dt = " << s.dt << " s >= " << limit
        << " s, the two-body limit 2/omega of the stiffest contact";
    throw InputError(msg.str());
  }
  checkedLimit_ = limit;
  checkedStep_ = s.step;
}

void NewtonIntegrator::apply(Scene& s) {
  require(s.dt > 0, "the time step must be > 0 (add a TimeStepper or set scene.dt)");
  require(damping >= 0 && damping < 1, "damping must lie in [0, 1)");
  checkStability(s);
  const bool clumps = s.hasClumps(), rot = !s.blockRotations;
  if (rot) {
    if (clumps) integrate<true, true>(s); else integrate<true, false>(s);
  } else {
    if (clumps) integrate<false, true>(s); else integrate<false, false>(s);
  }
}

}  // namespace trueaniso
