#include "control/RadiusExpansion.hpp"

#include <algorithm>
#include <cmath>

#include "control/CellServoLaw.hpp"
#include "core/Parallel.hpp"
#include "measure/Stress.hpp"

namespace trueaniso {

void RadiusExpansion::apply(Scene& s) {
  require(targetPressure > 0, "radius expansion target pressure must be > 0");
  require(gain > 0 && gain <= 1, "radius expansion gain must lie in (0, 1]");
  require(!holdDeviator || (deviatorGain > 0 && deviatorGain <= 1), "radius expansion deviator gain must lie in (0, 1]");
  const int nb = s.bodies.size();
  const bool clumps = s.hasClumps();
  if (base_.size() != s.members.radius.size() || baseMass_.size() != static_cast<size_t>(nb)) {
    base_ = s.members.radius;
    baseOffset_ = s.members.offset;
    baseMass_ = s.bodies.mass;
    baseInertia_ = s.bodies.inertia;
    baseVolume_ = s.bodies.volume;
    scale = 1.0;
  }
  // Measured before the radii grow: the forces, hence the stress and the unbalanced force, are
  // those of the last force evaluation either way.
  const ContactMeasures measured = cellMeasures(s);
  pressure = measured.stress.trace() / 3.0;
  const Real K = measured.stiffness.head<3>().mean();
  const Vec3 normal = measured.stress.diagonal();
  deviator = (normal.array() - pressure).abs().maxCoeff();
  const Real stepScale = s.stepScale();
  if (holdDeviator) s.cell.velGrad = deviatorGradient(normal, measured.stiffness.head<3>(), s.dt, stepScale);
  const Real err = targetPressure - pressure;
  // Growing radii by d ln r is, for the contacts, an isotropic affine compression of d ln r.
  const Real stepGain = CellServoLaw{gain, maxGrowthRate}.perStep(stepScale).gain;
  Real rate = K > 0 ? stepGain * err / (K * s.dt) : (err > 0 ? maxGrowthRate : -maxGrowthRate);
  rate = std::clamp(rate, -maxGrowthRate, maxGrowthRate);
  const Real grow = 1.0 + rate * s.dt;
  scale *= grow;
  // The clumps' loops and the contacts' below set each item from its own values: on the team,
  // the same bits. Serial, they would be work the second thread of a preparation waits through
  // every step. Not the spheres': setSphereRadius checks its input, and an exception cannot leave a team.
  if (clumps) growClumps(s);
  else for (int b = 0; b < nb; ++b) s.setSphereRadius(b, scale * base_[b]);
  Real* const rbar = s.contacts.rbar.data();
  const int nc = s.contacts.size();
#pragma omp parallel for schedule(static) if (worthThreads(nc))
  for (int c = 0; c < nc; ++c) rbar[c] *= grow;  // Eq. (7) is homogeneous in the radii
  unbalanced = measured.unbalanced;
  reached = std::abs(err) < stressTolerance && unbalanced < unbalancedTolerance &&
            (!holdDeviator || deviator < stressTolerance);
  if (reached && stopWhenReached) done = true;
}

}  // namespace trueaniso

namespace trueaniso {

Mat3 RadiusExpansion::deviatorGradient(const Vec3& normal, const Vec3& stiffness, Real dt, Real stepScale) const {
  // Before the network carries load along every axis there is no stiffness to turn an error into
  // a strain (CellServoLaw would then strain at its cap): the cell waits.
  if (!(stiffness.minCoeff() > 0)) return Mat3::Zero();
  const Real p = normal.mean();
  const Real stepGain = CellServoLaw{deviatorGain, maxGrowthRate}.perStep(stepScale).gain;
  Vec3 rate;
  for (int k = 0; k < 3; ++k)  // compression positive: an axis above the mean extends
    rate[k] = std::clamp(stepGain * (normal[k] - p) / (stiffness[k] * dt), -maxGrowthRate, maxGrowthRate);
  Mat3 L = Mat3::Zero();
  L.diagonal() = rate.array() - rate.mean();
  return L;
}

void RadiusExpansion::growClumps(Scene& s) const {
  const Real f3 = scale * scale * scale, f5 = f3 * scale * scale;
  const int nm = s.members.size(), nb = s.bodies.size();
#pragma omp parallel for schedule(static) if (worthThreads(nm))
  for (int m = 0; m < nm; ++m) {
    s.members.radius[m] = scale * base_[m];
    s.members.offset[m] = scale * baseOffset_[m];
  }
#pragma omp parallel for schedule(static) if (worthThreads(nb))
  for (int b = 0; b < nb; ++b) {
    s.bodies.mass[b] = f3 * baseMass_[b];
    s.bodies.inertia[b] = f5 * baseInertia_[b];
    s.bodies.volume[b] = f3 * baseVolume_[b];
  }
  s.refreshMembers();  // members moved with their offsets
}

}  // namespace trueaniso
