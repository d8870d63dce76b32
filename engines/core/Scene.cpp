#include "core/Scene.hpp"

#include <algorithm>
#include <cmath>

#include "clump/ClumpTemplate.hpp"
#include "core/Parallel.hpp"

namespace trueaniso {

namespace {
constexpr Real kPi = 3.14159265358979323846;
Real sphereVolume(Real r) { return 4.0 / 3.0 * kPi * r * r * r; }
}  // namespace

int Scene::addSphere(const Vec3& pos, Real radius) {
  require(radius > 0 && std::isfinite(radius), "sphere radius must be > 0");
  require(pos.allFinite(), "sphere position must be finite");
  const int b = bodies.size();
  const Real m = material.density * sphereVolume(radius);
  bodies.pos.push_back(pos);
  bodies.mass.push_back(m);
  bodies.inertia.push_back(Vec3::Constant(0.4 * m * radius * radius));
  bodies.volume.push_back(sphereVolume(radius));
  bodies.orientation.push_back(Quat::Identity());
  bodies.memberBegin.push_back(members.size() + 1);
  bodies.resizeDynamics();
  members.body.push_back(b);
  members.offset.push_back(Vec3::Zero());
  members.radius.push_back(radius);
  members.pos.push_back(pos);
  detectionInvalid = true;
  return b;
}

int Scene::addClump(const Vec3& pos, const Quat& orientation, const ClumpTemplate& shape, Real scale) {
  require(std::isfinite(scale) && scale > 0, "clump scale must be a finite number > 0");
  require(shape.size() > 0 && shape.volume > 0, "clump template is empty");
  const ClumpTemplate t = shape.scaled(scale);
  const Real rho = material.density;
  return addBody(pos, orientation, t.offsets, t.radii, rho * t.volume, rho * t.inertia, t.volume);
}

int Scene::addClump(const Vec3& pos, const Quat& orientation, const std::vector<Vec3>& offsets,
                    const std::vector<Real>& radii, Real mass, const Vec3& inertia, Real volume) {
  require(std::isfinite(mass) && mass > 0 && inertia.allFinite() && (inertia.array() > 0).all(),
          "clump mass and inertia must be finite and > 0");
  require(std::isfinite(volume) && volume >= 0, "clump volume must be finite and > 0 (or 0: the members' union)");
  if (volume > 0) validateClumpMembers(offsets, radii);
  else volume = cachedClumpVolume(offsets, radii);
  return addBody(pos, orientation, offsets, radii, mass, inertia, volume);
}

int Scene::addBody(const Vec3& pos, const Quat& orientation, const std::vector<Vec3>& offsets,
                   const std::vector<Real>& radii, Real mass, const Vec3& inertia, Real volume) {
  require(pos.allFinite(), "clump position must be finite");
  require(orientation.coeffs().allFinite() && orientation.norm() > 0, "clump orientation must be a finite quaternion");
  const int b = bodies.size();
  bodies.pos.push_back(pos);
  bodies.mass.push_back(mass);
  bodies.inertia.push_back(inertia);
  bodies.volume.push_back(volume);
  bodies.orientation.push_back(unitQuaternion(orientation));
  for (size_t k = 0; k < offsets.size(); ++k) {
    members.body.push_back(b);
    members.offset.push_back(offsets[k]);
    members.radius.push_back(radii[k]);
    members.pos.push_back(pos + bodies.orientation.back() * offsets[k]);
  }
  bodies.memberBegin.push_back(members.size());
  bodies.resizeDynamics();
  detectionInvalid = true;
  return b;
}

void Scene::setSphereRadius(int b, Real radius) {
  require(bodies.memberCount(b) == 1, "setSphereRadius applies to single spheres only");
  require(radius > 0, "sphere radius must be > 0");
  const Real m = material.density * sphereVolume(radius);
  bodies.mass[b] = m;
  bodies.inertia[b] = Vec3::Constant(0.4 * m * radius * radius);
  bodies.volume[b] = sphereVolume(radius);
  members.radius[bodies.memberBegin[b]] = radius;
}

void Scene::refreshMembers() {
  const int nb = bodies.size();
  if (!hasClumps()) {
    members.pos = bodies.pos;
    return;
  }
#pragma omp parallel for schedule(static) if (worthThreads(nb))
  for (int b = 0; b < nb; ++b) {
    const Quat& q = bodies.orientation[b];
    for (int m = bodies.memberBegin[b]; m < bodies.memberBegin[b + 1]; ++m)
      members.pos[m] = bodies.pos[b] + q * members.offset[m];
  }
}

void Scene::rescale(Real f) {
  require(f > 0 && std::isfinite(f), "rescale factor must be > 0");
  const Real f2 = f * f, f3 = f2 * f;
  measured.clear();  // the forces and branches scale
  cell.hSize *= f;
  cell.refHSize *= f;
  for (int b = 0; b < bodies.size(); ++b) {
    bodies.pos[b] *= f;
    bodies.vel[b] *= f;  // same strain rate field, same angular velocities
    bodies.mass[b] *= f3;
    bodies.inertia[b] *= f3 * f2;
    bodies.volume[b] *= f3;
    bodies.force[b] *= f2;
    bodies.torque[b] *= f3;
  }
  for (int m = 0; m < members.size(); ++m) {
    members.offset[m] *= f;
    members.radius[m] *= f;
    members.pos[m] *= f;
  }
  // Spheres: mass and inertia recomputed from the new radius (not scaled), so that a scene saved
  // and loaded again from its radii has the very same masses, to the last bit.
  for (int b = 0; b < bodies.size(); ++b)
    if (bodies.memberCount(b) == 1 && members.offset[bodies.memberBegin[b]].isZero())
      setSphereRadius(b, members.radius[bodies.memberBegin[b]]);
  Contacts& C = contacts;
  for (int c = 0; c < C.size(); ++c) {
    C.rbar[c] *= f; C.overlap[c] *= f;
    C.normalForce[c] *= f2; C.shearForce[c] *= f2;
    C.rollingMoment[c] *= f2 * f;  // a force times a length (k_r ~ f^3, its cap eta_r rbar N too)
  }
  for (Vec3& x : C.evaluation.pos) x *= f;  // the branch vectors scale with them
  C.evaluation.hSize *= f;
  detectionInvalid = true;
}

Real Scene::solidVolume() const {
  Real v = 0;
  for (Real x : bodies.volume) v += x;
  return v;
}

Real Scene::maxRadius() const {
  return members.radius.empty() ? 0.0 : *std::max_element(members.radius.begin(), members.radius.end());
}

void Scene::setDensity(Real density) {
  require(std::isfinite(density) && density > 0, "density must be a finite number > 0");
  const Real f = density / material.density;
  material.density = density;
  for (int b = 0; b < bodies.size(); ++b) {
    bodies.mass[b] *= f;
    bodies.inertia[b] *= f;
  }
}

void Scene::validate() const {
  material.validate();
  require(bodies.size() > 0, "the scene has no particles");
  cell.validate();
  require(solidVolume() < cell.volume(),
          "the particles' volume exceeds the cell's: the size distribution cannot fit the box");
}

}  // namespace trueaniso
