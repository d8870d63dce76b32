#include "boundary/RigidWalls.hpp"

#include <cmath>
#include <sstream>

#include "measure/Stress.hpp"

namespace trueaniso {

void RigidWalls::setBox(const Vec3& lower, const Vec3& upper) {
  lo = lower;
  hi = upper;
  refWidth = upper - lower;
  rate.setZero();
}

Real RigidWalls::area(int axis) const {
  const Vec3 w = width();
  return w[(axis + 1) % 3] * w[(axis + 2) % 3];
}

Vec3 RigidWalls::stress() const {
  Vec3 s;
  for (int k = 0; k < 3; ++k) s[k] = 0.5 * (force[2 * k] + force[2 * k + 1]) / area(k);
  return s;
}

Real RigidWalls::normalForce(const Material& m, Real radius, Real overlap) {
  if (!(overlap > 0)) return 0;
  const Real wallModulus = 2.0 * m.contactModulus();  // 2 G / (1 - nu)
  return 4.0 / 3.0 * wallModulus * std::sqrt(radius) * overlap * std::sqrt(overlap);
}

CellMeasurement RigidWalls::measurement(const Scene& s) const {
  CellMeasurement m;
  const Vec3 sig = stress();
  const Vec3 w = width();
  for (int k = 0; k < 3; ++k) {
    m.stress[k] = sig[k];
    m.stiffness[k] = (stiffness[2 * k] + stiffness[2 * k + 1]) * w[k] / (4.0 * area(k));
  }
  m.deformation = w.cwiseQuotient(refWidth).asDiagonal();
  m.unbalanced = unbalancedForce(s);
  return m;
}

void RigidWalls::validate(const Scene& s) const {
  std::ostringstream msg;
  const Vec3 w = width();
  if (!lo.allFinite() || !hi.allFinite() || !rate.allFinite()) msg << "rigid walls: positions and rates must be finite";
  else if (!(w.array() > 0).all()) msg << "rigid walls: every upper wall must lie above its lower wall";
  else if (!(refWidth.array() > 0).all()) msg << "rigid walls: the reference gaps must be > 0";
  else if (!Cell::isDiagonal(s.cell.hSize) || !s.cell.velGrad.isZero())
    msg << "rigid walls: the periodic cell must be a fixed orthorhombic box (velGrad 0); the walls load the specimen";
  else if (!(margin >= 0)) msg << "rigid walls: the margin must be >= 0";
  else {
    // The box must sit inside the cell [0, h_k) with room for a diameter plus the margin on the
    // periodic side, so that no sphere reaches an image of one at the opposite wall.
    const Real need = 2 * s.maxRadius() + margin;
    for (int k = 0; k < 3; ++k) {
      const Real h = s.cell.hSize(k, k);
      if (lo[k] < 0 || hi[k] > h || h - w[k] <= need) {
        msg << "rigid walls: on axis " << k << " the box [" << lo[k] << ", " << hi[k] << "] must lie in the cell [0, " << h
            << "] and leave more than the largest diameter plus the margin (" << need << " m) outside it";
        break;
      }
    }
  }
  if (!msg.str().empty()) throw InputError(msg.str());
}

void RigidWalls::addForces(Scene& s) {
  force.setZero();
  stiffness.setZero();
  contacts.setZero();
  maxOverlap = 0;
  s.measured.clear();  // the bodies' resultants change: the force loop's sums no longer hold them
  const Members& M = s.members;
  Bodies& B = s.bodies;
  const bool clumps = s.hasClumps();
  for (int m = 0; m < M.size(); ++m) {
    const Vec3& x = M.pos[m];
    const Real r = M.radius[m];
    const int b = M.body[m];
    for (int k = 0; k < 3; ++k) {
      for (int side = 0; side < 2; ++side) {
        // Overlap with the wall, and the direction of its push on the sphere (+e_k from lo).
        const Real overlap = side == 0 ? r - (x[k] - lo[k]) : r - (hi[k] - x[k]);
        if (!(overlap > 0)) continue;
        const Real N = normalForce(s.material, r, overlap);
        const Real dir = side == 0 ? 1.0 : -1.0;
        Vec3 f = Vec3::Zero();
        f[k] = dir * N;
        B.force[b] += f;
        if (clumps) B.torque[b] += (x - B.pos[b]).cross(f);
        const int w = 2 * k + side;
        force[w] += N;
        stiffness[w] += 1.5 * N / overlap;
        ++contacts[w];
        maxOverlap = std::max(maxOverlap, overlap);
      }
    }
  }
}

void RigidWalls::apply(Scene& s) {
  validate(s);
  const Vec3 w = width();
  for (int k = 0; k < 3; ++k) {
    const Real half = 0.5 * rate[k] * w[k] * s.dt;
    lo[k] -= half;
    hi[k] += half;
  }
  addForces(s);
}

WallServo::WallServo(std::shared_ptr<RigidWalls> w, std::shared_ptr<TrueTriaxialServo> p)
    : walls(std::move(w)), path(std::move(p)) {
  require(walls != nullptr && path != nullptr, "WallServo needs walls and a path servo");
}

void WallServo::start(Scene& s) {
  require(!path->controlShear, "WallServo: walls carry no shear stress; turn the path's shear control off");
  path->start(s);
}

void WallServo::apply(Scene& s) {
  if (path->status == TrueTriaxialServo::Status::Reached || path->status == TrueTriaxialServo::Status::Failed) {
    done = true;
    return;
  }
  require(!path->controlShear, "WallServo: walls carry no shear stress; turn the path's shear control off");
  path->stepScale = s.stepScale();
  const Vec6 r = path->update(walls->measurement(s), s.dt);
  walls->rate = r.head<3>();
  if (path->done) done = true;
}

}  // namespace trueaniso
