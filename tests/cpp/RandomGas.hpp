#pragma once
// Random test scenes: n spheres (radii 0.8-1.2 r, overlaps allowed) at solid fraction phi in a
// periodic cell of the given shape (and dimers, randomDimers), placed uniformly in reduced coordinates so that the cell's
// shape does not bias where they sit. One home for the scenes the stepper and cell tests share.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "Drivers.hpp"
#include "clump/ClumpTemplate.hpp"
#include "core/Scene.hpp"

namespace trueaniso::testing {

inline std::shared_ptr<Scene> randomGasIn(const Mat3& shape, int n, Real phi, unsigned seed, Real r = 1e-4) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<Real> U(0, 1);
  std::vector<Real> radii(n);
  Real vol = 0;
  for (Real& x : radii) { x = r * (0.8 + 0.4 * U(gen)); vol += 4.0 / 3.0 * M_PI * x * x * x; }
  const Mat3 h = shape * std::cbrt(vol / phi / shape.determinant());
  s->cell.hSize = s->cell.refHSize = h;
  // (The argument order of the three draws is the compiler's; kept as the tests were tuned with.)
  for (int i = 0; i < n; ++i) s->addSphere(h * Vec3(U(gen), U(gen), U(gen)), radii[i]);
  return s;
}

// n asymmetric dimers (balls r and 0.7 r, centres 1.1 r apart) at solid fraction phi in a cubic
// periodic cell, placed and turned at random (overlaps allowed): the branch vectors join clump
// centres, not the touching members.
inline std::shared_ptr<Scene> randomDimers(int n, Real phi, unsigned seed, Real r = 1e-4) {
  const ClumpTemplate dimer = makeClumpTemplate({Vec3::Zero(), Vec3(1.1 * r, 0, 0)}, {r, 0.7 * r});
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real side = std::cbrt(n * dimer.volume / phi);
  s->cell.setBox(Vec3::Constant(side));
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<Real> U(0, 1);
  for (int k = 0; k < n; ++k) {
    const Vec3 at = side * Vec3(U(gen), U(gen), U(gen));
    const Vec3 axis = Vec3(U(gen) - 0.5, U(gen) - 0.5, U(gen) - 0.5).normalized();
    s->addClump(at, Quat(Eigen::AngleAxisd(6.28 * U(gen), axis)), dimer);
  }
  return s;
}

}  // namespace trueaniso::testing
