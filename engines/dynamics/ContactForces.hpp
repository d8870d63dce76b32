#pragma once
// Contact forces of the simplified Hertz-Mindlin law on every listed pair, added to the two
// bodies as they are computed. Threads accumulate into their own body buffers (thread 0 into the
// bodies' arrays), summed in thread order afterwards: no atomics, no write conflicts, and a
// result that is bit-identical from run to run for a given number of threads.
#include <vector>

#include "contact/HertzMindlin.hpp"
#include "core/Engine.hpp"

namespace trueaniso {

class ContactForces : public Engine {
 public:
  void apply(Scene& scene) override;
  std::string name() const override { return "ContactForces"; }
  long slidingContacts = 0;  // contacts at the Coulomb cap in the last evaluation
  long rollingCapped = 0;    // contacts at the rolling cap in the last evaluation (rolling on)

 private:
  // Sheared: a cell with off-diagonal hSize or velGrad (core/Cell.hpp); the orthorhombic
  // instantiation keeps the diagonal cell's cost. Rolling: the rolling sub-model of the contact
  // law (Material::rolling; single spheres with free rotations only); off, the loop is the
  // paper's law alone, its machine code untouched by the option.
  template <bool Clumps, bool Rotations, bool Sheared, bool Rolling = false>
  void compute(Scene& scene, const HertzMindlin& law);
  std::vector<std::vector<Vec3>> forceBuffers_, torqueBuffers_;  // threads 1..n-1
  std::vector<CellSums> pairSums_;  // the cell measures' sums per block of pairs (measure/CellSums.hpp)
  std::vector<Real> bodySums_;      // ... and of bodies
};

}  // namespace trueaniso
