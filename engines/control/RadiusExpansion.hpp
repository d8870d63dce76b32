#pragma once
// Radius expansion at a fixed cell: all radii grow (or shrink) by a common factor, servoed on
// the mean stress, until the target mean stress is held in equilibrium. The factor is relative to
// the radii when the engine was attached; Scene::rescale then restores the size distribution
// exactly, which Hertz contacts allow without changing any stress (see Scene.hpp).
// A clump grows as a whole, about its centre of mass: member radii and offsets by the factor, its
// volume and mass by its cube, its inertia by its fifth power, so its shape never changes.
#include <vector>

#include "core/Engine.hpp"

namespace trueaniso {

class RadiusExpansion : public Engine {
 public:
  Real targetPressure = 100e3;   // Pa
  Real gain = 0.01;
  Real maxGrowthRate = 1.0;      // d ln r / dt cap (1/s)
  Real stressTolerance = 100.0;  // Pa
  Real unbalancedTolerance = 1e-3;
  bool stopWhenReached = false;

  Real scale = 1.0;              // current radius / base radius
  Real pressure = 0, unbalanced = 0;
  bool reached = false;

  void apply(Scene& scene) override;
  std::string name() const override { return "RadiusExpansion"; }

 private:
  void growClumps(Scene& scene) const;
  std::vector<Real> base_;       // member radii when attached
  // Clumps when attached: member offsets, body mass, inertia and volume.
  std::vector<Vec3> baseOffset_, baseInertia_;
  std::vector<Real> baseMass_, baseVolume_;
};

}  // namespace trueaniso
