#pragma once
// The scene owns the particles, the cell and the contacts; engines own only their parameters
// and state (as YADE's Scene and O.engines).
#include <vector>

#include "core/Bodies.hpp"
#include "core/Cell.hpp"
#include "core/Contacts.hpp"
#include "core/Material.hpp"
#include "measure/CellSums.hpp"

namespace trueaniso {
struct ClumpTemplate;
}

namespace trueaniso {

struct Scene {
  Cell cell;
  Material material;
  Bodies bodies;
  Members members;
  Contacts contacts;

  Real dt = 0;       // time step; set by TimeStepper or by the user
  // The step the reference rule (the smallest-inertia bound at its factor, TimeStepper) would take
  // now: the unit of time of the servos' per-step settings (path rate, gain, step counts), so that
  // a longer step under another rule loads at the same rate in time. 0: unknown, the step is the unit.
  Real referenceDt = 0;
  Real time = 0;
  long step = 0;
  bool blockRotations = false;  // scene-wide: no angular velocity is integrated
  // Set whenever something outside the integrator moves bodies, changes radii or the cell,
  // so that the contact detection rebuilds its list before the next force evaluation.
  bool detectionInvalid = true;
  // The cell measures' sums of the last force evaluation, in the steps an engine reads them
  // (measure/CellSums.hpp). Whatever changes the bodies' forces after the contact loop (walls, a
  // rescale, a renumbering) clears them, and the measures are then summed apart.
  MeasuredSums measured;

  // dt in units of referenceDt (1 while referenceDt is unknown).
  Real stepScale() const { return referenceDt > 0 ? dt / referenceDt : 1.0; }

  int addSphere(const Vec3& pos, Real radius);
  // A rigid clump of a template's shape (clump/ClumpTemplate.hpp), its lengths times `scale`:
  // mass and inertia from the union's volume and moments and the material's density.
  int addClump(const Vec3& pos, const Quat& orientation, const ClumpTemplate& shape, Real scale = 1.0);
  // A rigid clump with given member offsets (body frame, about the centre of mass), mass and
  // principal inertia (a saved scene, YADE's clumps). Its solid volume is `volume` when given
  // (> 0: a saved scene's own, so that every process that loads it gets the same bits), else
  // the union's, from CGAL (cached per shape, cachedClumpVolume, whose last bits depend on which
  // clump of the shape the process met first). Members are validated as for a template.
  int addClump(const Vec3& pos, const Quat& orientation, const std::vector<Vec3>& offsets,
               const std::vector<Real>& radii, Real mass, const Vec3& inertia, Real volume = 0);
  // Single spheres only: change the radius and the mass and inertia that follow from it.
  void setSphereRadius(int body, Real radius);
  // The material's density, with every body's mass and inertia scaled to it (they are
  // proportional to the density for spheres and clumps alike).
  void setDensity(Real density);

  bool hasClumps() const { return members.size() != bodies.size(); }
  // Member world positions from body positions and orientations (clumps only; for single
  // spheres the member position is the body position and is kept equal by this call).
  void refreshMembers();

  // Geometric similarity x -> f x of the whole scene (cell, positions, radii, clump offsets).
  // Hertz-Mindlin forces scale as f^2 (N ~ sqrt(R) delta^1.5, k_s ~ sqrt(R delta)) and lengths
  // as f, so every stress is unchanged and an equilibrium stays one: this is how a specimen made
  // by radius expansion is brought back to the exact size distribution. Masses scale as f^3.
  void rescale(Real f);

  Real solidVolume() const;  // sum of the bodies' solid volumes (clumps: their union, Bodies::volume)
  Real maxRadius() const;
  void validate() const;     // throws InputError for an unusable scene

 private:
  int addBody(const Vec3& pos, const Quat& orientation, const std::vector<Vec3>& offsets,
              const std::vector<Real>& radii, Real mass, const Vec3& inertia, Real volume);
};

}  // namespace trueaniso
