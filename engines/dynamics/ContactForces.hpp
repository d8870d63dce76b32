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

 private:
  template <bool Clumps, bool Rotations>
  void compute(Scene& scene, const HertzMindlin& law);
  std::vector<std::vector<Vec3>> forceBuffers_, torqueBuffers_;  // threads 1..n-1
};

}  // namespace trueaniso
