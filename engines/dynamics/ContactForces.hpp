#pragma once
// Contact forces of the simplified Hertz-Mindlin law on every listed pair, then gathered per
// body. Two passes (pairs, then bodies through the incidence lists) avoid write conflicts and
// atomics, and make the result independent of the number of threads.
#include "contact/HertzMindlin.hpp"
#include "dynamics/Engine.hpp"

namespace trueaniso {

class ContactForces : public Engine {
 public:
  void apply(Scene& scene) override;
  std::string name() const override { return "ContactForces"; }
  long slidingContacts = 0;  // contacts at the Coulomb cap in the last evaluation

 private:
  template <bool Clumps, bool Rotations>
  void computePairs(Scene& scene, const HertzMindlin& law);
  void gather(Scene& scene) const;
};

}  // namespace trueaniso
