#pragma once
// Verlet list with a skin on the periodic box, built with cell lists. The list holds every pair
// of member spheres (of different bodies) closer than r1 + r2 + skin; it is rebuilt only when
// the motion since the last build could have brought a pair outside the list into contact.
#include <vector>

#include "core/Engine.hpp"

namespace trueaniso {

class ContactDetection : public Engine {
 public:
  // Skin as a fraction of the largest member radius. Quasi-static runs move little per step,
  // so a modest skin keeps the list short and still rebuilds rarely.
  Real skinFactor = 0.2;

  void apply(Scene& scene) override;
  std::string name() const override { return "ContactDetection"; }

  bool needsRebuild(const Scene& scene) const;
  void rebuild(Scene& scene);

  long rebuilds = 0;
  // Active contacts that were not found again at a rebuild; always 0 unless the skin criterion
  // is broken, and checked by the tests.
  long lostContacts = 0;

 private:
  std::vector<Vec3> refPos_;    // member positions at the last build
  std::vector<Real> refRadius_;
  Vec3 refSize_ = Vec3::Ones();
  Real skin_ = 0;
};

}  // namespace trueaniso
