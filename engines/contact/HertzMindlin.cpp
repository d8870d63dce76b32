#include "contact/HertzMindlin.hpp"

#include <cmath>

namespace trueaniso {

void HertzMindlin::evaluate(Batch& q, int m) const {
  const Real ksUnit = ratio_ * 1.5;
  for (int k = 0; k < m; ++k) {
    const Real sqrtDelta = std::sqrt(q.delta[k]);
    const Real coef = hertzUnit_ * std::sqrt(q.rbar[k]);
    const Real N = coef * q.delta[k] * sqrtDelta;
    const Real ks = ksUnit * coef * sqrtDelta;
    Real fx = q.fx[k], fy = q.fy[k], fz = q.fz[k];
    carry(fx, fy, fz, q.px[k], q.py[k], q.pz[k], q.nx[k], q.ny[k], q.nz[k], q.twist[k]);
    const bool loaded = q.loaded[k] != 0;
    fx = (loaded ? fx : 0.0) - ks * q.ux[k];
    fy = (loaded ? fy : 0.0) - ks * q.uy[k];
    fz = (loaded ? fz : 0.0) - ks * q.uz[k];
    // Coulomb: |Fs| <= mu N (the slack: kCapSlack); the few that slide are scaled below.
    const Real cap = mu_ * N;
    const Real f2 = fx * fx + fy * fy + fz * fz;
    q.fx[k] = fx;
    q.fy[k] = fy;
    q.fz[k] = fz;
    q.N[k] = N;
    q.sliding[k] = beyondCap(f2, cap) ? 1.0 : 0.0;
  }
  // Apart, because its square root and division, computed for every contact, cost the loop
  // above 8 % of the force loop's time (perf) for the 1-2 % of contacts that slide.
  for (int k = 0; k < m; ++k) {
    if (q.sliding[k] == 0) continue;
    const Real cap = mu_ * q.N[k];
    const Real scale = capScale(q.fx[k] * q.fx[k] + q.fy[k] * q.fy[k] + q.fz[k] * q.fz[k], cap);
    q.fx[k] *= scale;
    q.fy[k] *= scale;
    q.fz[k] *= scale;
  }
}

}  // namespace trueaniso
