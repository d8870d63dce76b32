#include "dynamics/NewtonIntegrator.hpp"

#include <sstream>

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

}  // namespace

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
#pragma omp parallel for schedule(static)
  for (int b = 0; b < nb; ++b) {
    Vec3 acc = B.force[b] / B.mass[b];
    if (damp != 0) dampLocal(acc, B.vel[b], dt, damp);
    B.vel[b] += dt * acc;
    B.pos[b] = (sheared ? Vec3(map * B.pos[b]) : Vec3(B.pos[b].cwiseProduct(stretch))) + dt * B.vel[b];
    if (!Rotations) continue;
    if (!Clumps || B.memberCount(b) == 1) {
      // A sphere's inertia is isotropic: no orientation to track, nothing reads it.
      Vec3 angAcc = B.torque[b] / B.inertia[b].x();
      if (damp != 0) dampLocal(angAcc, B.angVel[b], dt, damp);
      B.angVel[b] += dt * angAcc;
    } else {
      // Rigid clump: Euler's equations in the body frame, then advance the orientation.
      const Quat& q = B.orientation[b];
      const Vec3 I = B.inertia[b];
      const Vec3 wBody = q.conjugate() * B.angVel[b];
      const Vec3 tBody = q.conjugate() * B.torque[b];
      Vec3 angAcc = (tBody - wBody.cross(I.cwiseProduct(wBody))).cwiseQuotient(I);
      angAcc = q * angAcc;
      if (damp != 0) dampLocal(angAcc, B.angVel[b], dt, damp);
      B.angVel[b] += dt * angAcc;
      const Vec3 w = B.angVel[b];
      const Real angle = w.norm() * dt;
      if (angle > 0) B.orientation[b] = (Quat(Eigen::AngleAxisd(angle, w / w.norm())) * q).normalized();
    }
  }
  s.cell.hSize = sheared ? Mat3(map * s.cell.hSize) : Mat3(stretch.asDiagonal() * s.cell.hSize);
  if (Clumps) s.refreshMembers();
  else s.members.pos = B.pos;  // kept equal for engines that read member positions
}

void NewtonIntegrator::checkStability(const Scene& s) {
  if (s.dt == checkedDt_ && s.step - checkedStep_ < checkEvery) return;
  const Real limit = TimeStepper::criticalPairStep(s);
  if (s.dt >= limit) {
    std::ostringstream msg;
    msg << "unstable time step refused: dt = " << s.dt << " s >= " << limit
        << " s, the two-body limit 2/omega of the stiffest contact";
    throw InputError(msg.str());
  }
  checkedDt_ = s.dt;
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
