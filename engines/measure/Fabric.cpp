#include "measure/Fabric.hpp"

#include <cmath>
#include <limits>
#include <vector>

#include "measure/FabricTerms.hpp"
#include "measure/Reduce.hpp"

namespace trueaniso {

namespace {

constexpr Real kPi = 3.14159265358979323846;
constexpr Real kNaN = std::numeric_limits<Real>::quiet_NaN();

}  // namespace

Real Fabric::contactDensityEq36() const {
  if (!(meanRadiusCubed > 0)) return kNaN;
  return 3.0 * Zm / (8.0 * kPi * (1.0 + voidRatio) * meanRadiusCubed);
}

Fabric fabric(const Scene& s) {
  require(!s.detectionInvalid,
          "fabric needs the contacts of a force evaluation at the current configuration: run "
          "ContactDetection and ContactForces first (one step of the engine chain)");
  const Contacts& C = s.contacts;
  const Bodies& Bd = s.bodies;
  const int nc = C.size(), nb = Bd.size();

  C.requireEvaluated(nb, "fabric");
  FabricSums sum = blockSum<FabricSums>(nc, FabricSums{}, [&](int c, FabricSums& acc) {
    const Real N = C.normalForce[c];
    if (!(N > 0)) return;
    acc.add(N, C.rbar[c], C.normal[c], C.branch(c));
  });

  // Contacts per particle for Eq. (14). A serial pass over the pairs: it scatters into bodies, and
  // unlike contactsPerBody it does not need the incidence lists (absent on an imported list).
  Fabric f;
  std::vector<int> perBody(nb, 0);
  for (int c = 0; c < nc; ++c)
    if (C.normalForce[c] > 0) { ++perBody[C.b1[c]]; ++perBody[C.b2[c]]; }
  f.counts.particles = nb;
  for (int k : perBody) {
    if (k == 0) ++f.counts.noContact;
    if (k == 1) ++f.counts.oneContact;
  }
  sum.finish(f);
  f.Zm = f.counts.mechanical();

  f.volume = s.cell.volume();
  f.voidRatio = voidRatio(s);
  f.meanRadiusCubed = nb > 0 ? 3.0 * solidVolume(s) / (4.0 * kPi * nb) : kNaN;
  return f;
}

}  // namespace trueaniso
