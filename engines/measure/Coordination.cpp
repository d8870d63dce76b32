#include "measure/Coordination.hpp"

#include <cmath>
#include <limits>

#include "core/Parallel.hpp"
#include "dynamics/ContactDetection.hpp"
#include "measure/Reduce.hpp"

namespace trueaniso {

Real Coordination::mechanical() const {
  const long active = particles - noContact - oneContact;
  if (active <= 0) return std::numeric_limits<Real>::quiet_NaN();
  return (2.0 * contacts - oneContact) / active;
}

std::vector<int> contactsPerBody(const Scene& s) {
  const Contacts& C = s.contacts;
  const int nb = s.bodies.size();
  std::vector<int> count(nb, 0);
  if (C.incBegin.size() != static_cast<size_t>(nb) + 1) {
    // No incidence lists yet (contacts set from a file, no detection run): count from the pairs.
    for (int c = 0; c < C.size(); ++c)
      if (C.normalForce[c] > 0) { ++count[C.b1[c]]; ++count[C.b2[c]]; }
    return count;
  }
#pragma omp parallel for schedule(static) if (worthThreads(nb))
  for (int b = 0; b < nb; ++b) {
    int k = 0;
    for (int q = C.incBegin[b]; q < C.incBegin[b + 1]; ++q) {
      const int e = C.incidence[q];
      if (C.normalForce[e >= 0 ? e : ~e] > 0) ++k;
    }
    count[b] = k;
  }
  return count;
}

namespace {

// Eq. (14)'s counts from the contacts of each body.
Coordination fromCounts(const std::vector<int>& count) {
  Coordination z;
  z.particles = static_cast<long>(count.size());
  long ends = 0;
  for (int k : count) {
    ends += k;
    if (k == 0) ++z.noContact;
    if (k == 1) ++z.oneContact;
  }
  z.contacts = ends / 2;
  return z;
}

}  // namespace

Coordination coordination(const Scene& s) { return fromCounts(contactsPerBody(s)); }

std::vector<int> contactsPerBodyWithinGap(const Scene& s, Real tol) {
  require(std::isfinite(tol) && tol >= 0, "the gap tolerance must be a finite number >= 0");
  require(tol * 2.0 < 0.5 * kDefaultSkinFactor,
          "the gap tolerance must stay below a quarter of the Verlet skin factor (" +
              std::to_string(0.25 * kDefaultSkinFactor) + "): pairs farther apart may not be listed");
  const Contacts& C = s.contacts;
  const Members& M = s.members;
  std::vector<int> count(s.bodies.size(), 0);
  for (int c = 0; c < C.size(); ++c) {
    // overlap > -tol (r1 + r2) written so that a touching pair (normalForce > 0) always counts,
    // whatever round-off its overlap carries.
    if (C.normalForce[c] > 0 || C.overlap[c] > -tol * (M.radius[C.m1[c]] + M.radius[C.m2[c]])) {
      ++count[C.b1[c]];
      ++count[C.b2[c]];
    }
  }
  return count;
}

Coordination coordinationWithinGap(const Scene& s, Real tol) { return fromCounts(contactsPerBodyWithinGap(s, tol)); }

Real solidVolume(const Scene& s) {
  const Bodies& B = s.bodies;
  return blockSum<Real>(B.size(), 0.0, [&](int b, Real& acc) { acc += B.volume[b]; });
}

Real voidRatio(const Scene& s) {
  const Real solid = solidVolume(s);
  return (s.cell.volume() - solid) / solid;
}

}  // namespace trueaniso
