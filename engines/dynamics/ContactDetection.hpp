#pragma once
// Verlet list with a skin on the periodic cell, built with cell lists. The list holds every pair
// of member spheres (of different bodies) closer than r1 + r2 + skin; it is rebuilt only when
// the motion since the last build could have brought a pair outside the list into contact.
//
// The cell may be sheared (core/Cell.hpp): the grid's bins are boxes in reduced coordinates, as
// many along each cell vector as the distance between the cell's opposite faces holds bins of the
// interaction range, so that any pair within range sits in neighbouring bins. The skin criterion
// counts the cell's deformation since the last build (its affine map T, through |T - I|). A cell
// sheared so far that a pair of its vectors has |a_i . a_j| > flipThreshold |a_i|^2 is flipped at
// the next build (dynamics/CellFlip.hpp), keeping every contact's history.
#include <vector>

#include "core/Engine.hpp"

namespace trueaniso {

// The skin of every detection that does not set its own (contact refresh, the Python runner's
// default); measures that read non-touching listed pairs rely on it (measure/Coordination.hpp).
constexpr Real kDefaultSkinFactor = 0.2;

class ContactDetection : public Engine {
 public:
  // Skin as a fraction of the largest member radius. Quasi-static runs move little per step,
  // so a modest skin keeps the list short and still rebuilds rarely.
  Real skinFactor = kDefaultSkinFactor;

  void apply(Scene& scene) override;
  std::string name() const override { return "ContactDetection"; }

  bool needsRebuild(const Scene& scene) const;
  void rebuild(Scene& scene);

  // Flip the cell at a build when it has sheared this far (Cell::reduction); 0.55 rather than 0.5
  // so that a cell sheared back and forth around the half-way point does not flip every time.
  Real flipThreshold = 0.55;
  bool allowFlip = true;

  long rebuilds = 0;
  long flips = 0;
  // Active contacts that were not found again at a rebuild; always 0 unless the skin criterion
  // is broken, and checked by the tests.
  long lostContacts = 0;

 private:
  std::vector<Vec3> refPos_;    // member positions at the last build
  std::vector<Real> refRadius_;
  Mat3 refHSize_ = Mat3::Identity();  // hSize at the last build
  Real skin_ = 0;
};

}  // namespace trueaniso
