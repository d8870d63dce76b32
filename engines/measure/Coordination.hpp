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

// A contact count with a gap tolerance (the paper might count near-contacts): a listed
// pair counts when its gap -overlap is below tol (r1 + r2), tol times the pair's mean diameter;
// touching pairs (overlap > 0) always count. The same rattler rule then gives Zm_gap by Eq. (14).
// tol = 0 counts the touching pairs, as coordination() does.
// Reads Contacts::overlap of the listed, non-touching pairs, so it needs a scene whose forces were
// evaluated after its last detection (refreshContacts, or a step), as every measure here does.
// Right after a detection the list holds every pair closer than the skin kDefaultSkinFactor
// r_max; a tolerance reaching that far is refused (tol (r1 + r2) <= 2 tol r_max must stay below
// half the skin, the rest for the motion allowed between rebuilds).
constexpr Real kGapTolerance = 1e-3;  // default tol: Zm_gap1e-3 of the study's rows
Coordination coordinationWithinGap(const Scene& scene, Real tol = kGapTolerance);
std::vector<int> contactsPerBodyWithinGap(const Scene& scene, Real tol);

// V_s: the bodies' solid volumes summed in fixed blocks (thread-count independent); a clump's is
// the union of its member balls, overlaps counted once (Bodies::volume), never the members' sum.
Real solidVolume(const Scene& scene);
// e = (V - V_s)/V_s.
Real voidRatio(const Scene& scene);

}  // namespace trueaniso
