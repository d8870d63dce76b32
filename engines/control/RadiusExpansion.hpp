#pragma once
// Radius expansion at a fixed cell: all radii grow (or shrink) by a common factor, servoed on
// the mean stress, until the target mean stress is held in equilibrium. The factor is relative to
// the radii when the engine was attached; Scene::rescale then restores the size distribution
// exactly, which Hertz contacts allow without changing any stress (see Scene.hpp).
// A clump grows as a whole, about its centre of mass: member radii and offsets by the factor, its
// volume and mass by its cube, its inertia by its fifth power, so its shape never changes.
//
// holdDeviator: the cell also holds the three normal stresses at their mean while the radii grow,
// by a velocity gradient with no trace (the cell's volume is kept: the mean stress stays the
// growth's to servo) and no shear (the cell stays orthorhombic). Per axis the strain rate is the
// proportional law of CellServoLaw toward the measured mean, deviatorGain x (sigma_k - p) over the
// axis's affine stiffness, then less the mean of the three; capped at maxGrowthRate before the
// mean is taken out. Its own gain: a near-frictionless packing of elongated clumps resists a
// deviatoric strain far less than its affine estimate says (it rearranges), so the growth's gain
// leaves the deviator where the fixed cell has it (docs/clumps.md, "clump1 preparation"). A packing whose fabric makes one axis softer (a
// fixed cubic cell then carries less stress along it) is let relax that way during the growth
// instead of creeping towards it under the stage-2 servo. Off by default: the growth at a fixed
// cell, to the bit.
#include <vector>

#include "core/Engine.hpp"

namespace trueaniso {

class RadiusExpansion : public Engine {
 public:
  Real targetPressure = 100e3;   // Pa
  // Fractions of the stress errors closed per reference step (Scene::referenceDt), as the servos'
  // gains: a step stepScale reference steps long closes stepScale times as much (capped at the
  // whole error), so that the growth proceeds at the same rate in time under any time step rule
  // and grows the same packing, but for integration error, in fewer steps.
  Real gain = 0.01;
  Real maxGrowthRate = 1.0;      // d ln r / dt cap (1/s)
  Real stressTolerance = 100.0;  // Pa
  Real unbalancedTolerance = 1e-3;
  bool stopWhenReached = false;
  bool holdDeviator = false;
  Real deviatorGain = 0.05;      // per reference step too

  Real scale = 1.0;              // current radius / base radius
  Real pressure = 0, unbalanced = 0;
  // Largest |sigma_k - p| over the normal stresses (Pa), measured whether or not it is held; with
  // holdDeviator, reached asks it below stressTolerance too.
  Real deviator = 0;
  bool reached = false;

  void apply(Scene& scene) override;
  std::string name() const override { return "RadiusExpansion"; }
  bool readsCellMeasures() const override { return true; }

 private:
  void growClumps(Scene& scene) const;
  // The cell's velocity gradient that holds the normal stresses at their mean (holdDeviator).
  Mat3 deviatorGradient(const Vec3& normal, const Vec3& stiffness, Real dt, Real stepScale) const;
  std::vector<Real> base_;       // member radii when attached
  // Clumps when attached: member offsets, body mass, inertia and volume.
  std::vector<Vec3> baseOffset_, baseInertia_;
  std::vector<Real> baseMass_, baseVolume_;
};

}  // namespace trueaniso
