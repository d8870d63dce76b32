#pragma once
// Random test scenes: n spheres (radii 0.8-1.2 r, overlaps allowed) at solid fraction phi in a
// periodic cell of the given shape, placed uniformly in reduced coordinates so that the cell's
// shape does not bias where they sit. One home for the scenes the stepper and cell tests share.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "Drivers.hpp"
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

}  // namespace trueaniso::testing
