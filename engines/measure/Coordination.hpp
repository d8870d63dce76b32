#pragma once
// Particle-level counts of the contact network: the mechanical coordination number Zm of
// Eq. (14) and the void ratio. A particle is a body (a clump counts once); every member-member
// contact between two different bodies counts in Nc.
#include "core/Scene.hpp"

namespace trueaniso {

struct Coordination {
  long contacts = 0;       // N_c
  long particles = 0;      // N_p
  long noContact = 0;      // N_p^0
  long oneContact = 0;     // N_p^1
  // Eq. (14): (2 N_c - N_p^1) / (N_p - N_p^0 - N_p^1); NaN when no particle has 2 contacts.
  Real mechanical() const;
  Real plain() const { return particles ? 2.0 * contacts / particles : 0.0; }  // 2 N_c / N_p
};

Coordination coordination(const Scene& scene);
std::vector<int> contactsPerBody(const Scene& scene);

// V_s: the bodies' solid volumes summed in fixed blocks (thread-count independent); a clump's is
// the union of its member balls, overlaps counted once (Bodies::volume), never the members' sum.
Real solidVolume(const Scene& scene);
// e = (V - V_s)/V_s.
Real voidRatio(const Scene& scene);

}  // namespace trueaniso
