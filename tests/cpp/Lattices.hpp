#pragma once
// Lattices with closed-form elastic constants (docs/studies/statics.md, "Closed forms the tests compare with"): the simple cubic and the
// FCC lattice at uniform overlap, built in an orthorhombic cell of conventional cells, and the FCC
// lattice also in the sheared cell of its primitive vectors. Shared by the statics, the probes and
// the cell tests.
#include <cmath>
#include <memory>

#include "Drivers.hpp"
#include "contact/HertzMindlin.hpp"

namespace trueaniso::testing {

inline constexpr Real kR = 1e-4;  // sphere radius of the lattices (m)

// n^3 simple cubic lattice of spheres of radius r, spacing a_k = 2 r - delta_k along axis k.
inline std::shared_ptr<Scene> simpleCubic(int n, const Vec3& delta, Real r = kR) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Vec3 a = Vec3::Constant(2 * r) - delta;
  s->cell.setBox(n * a);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) s->addSphere(Vec3(i + 0.5, j + 0.5, k + 0.5).cwiseProduct(a), r);
  return s;
}

// n^3 conventional FCC cells (4 spheres each), nearest-neighbour distance l = 2 r - delta.
inline std::shared_ptr<Scene> fcc(int n, Real delta, Real r = kR) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real A = std::sqrt(2.0) * (2 * r - delta);
  s->cell.setBox(Vec3::Constant(n * A));
  const Vec3 basis[4] = {Vec3(0, 0, 0), Vec3(0.5, 0.5, 0), Vec3(0.5, 0, 0.5), Vec3(0, 0.5, 0.5)};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (const Vec3& b : basis) s->addSphere((Vec3(i, j, k) + b + Vec3::Constant(0.25)) * A, r);
  return s;
}

// Hertz-Mindlin of two equal spheres at overlap delta: N from Hertz, k_n and k_s from the paper's
// Eqs. (5)-(6) with rbar = r (independent of the 1.5 N/delta the code uses).
struct ContactLaw {
  Real N, kn, ks;
};
inline ContactLaw law(const Material& m, Real delta, Real r = kR) {
  const Real N = HertzMindlin(m).normalForce(delta, r);
  return {N, m.Cn() * std::cbrt(r * N), m.Cs() * std::cbrt(r * N)};
}

// Closed form of an orthorhombic simple cubic lattice (docs/studies/statics.md, "Simple cubic"): every
// sphere is an inversion centre, so translations stay affine; the rotations are uniform and
// set by moment balance, a series combination of the two shear springs of each shear plane.
inline Mat6 simpleCubicStiffness(const Material& m, const Vec3& delta, bool rotations, Real r = kR) {
  const Vec3 a = Vec3::Constant(2 * r) - delta;
  const Real V1 = a.prod();
  Vec3 kn, ks, sigma;
  for (int k = 0; k < 3; ++k) {
    const ContactLaw c = law(m, delta[k], r);
    kn[k] = c.kn;
    ks[k] = c.ks * a[k] * a[k];  // k_s a^2: shear spring times lever
    sigma[k] = c.N * a[k] / V1;
  }
  Mat6 C = Mat6::Zero();
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j) C(k, j) = k == j ? kn[k] * a[k] * a[k] / V1 : sigma[k];
  const int planes[3][2] = {{1, 2}, {0, 2}, {0, 1}};  // yz, xz, xy
  for (int I = 0; I < 3; ++I) {
    const Real k1 = ks[planes[I][0]], k2 = ks[planes[I][1]];
    const Real spring = rotations ? k1 * k2 / ((k1 + k2) * V1) : (k1 + k2) / (4 * V1);
    C(3 + I, 3 + I) = spring - 0.5 * (sigma[planes[I][0]] + sigma[planes[I][1]]);
  }
  return C;
}

// Closed form of an FCC lattice at uniform overlap (docs/studies/statics.md, "FCC").
inline Mat6 fccStiffness(const Material& m, Real delta, Real r = kR) {
  const ContactLaw c = law(m, delta, r);
  const Real l = 2 * r - delta, f = std::sqrt(2.0) / l, g = c.N / l;
  Mat6 C = Mat6::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) C(i, j) = i == j ? f * (c.kn + c.ks - g) : f * (0.5 * (c.kn - c.ks) + 2.5 * g);
  for (int I = 3; I < 6; ++I) C(I, I) = f * (0.5 * (c.kn + c.ks) - 1.5 * g);
  return C;
}

// The same FCC lattice (nearest-neighbour distance l = 2 r - delta, its cube axes along x, y, z)
// in the cell of n x n x n primitive cells: cell vectors n (A/2)(0,1,1), n (A/2)(1,0,1),
// n (A/2)(1,1,0), 60 degrees apart, one sphere per primitive cell.
inline std::shared_ptr<Scene> fccPrimitive(int n, Real delta, Real r = kR) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real A = std::sqrt(2.0) * (2 * r - delta);
  Mat3 p;
  p << 0, 1, 1, 1, 0, 1, 1, 1, 0;
  p *= 0.5 * A;
  s->cell.hSize = s->cell.refHSize = n * p;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) s->addSphere(p * Vec3(i + 0.3, j + 0.3, k + 0.3), r);
  return s;
}

}  // namespace trueaniso::testing
