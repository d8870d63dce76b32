#pragma once
// Scenes with known contacts for the fabric and micromechanics tests, and a brute-force reference
// of every contact computed from positions alone (not from the Contacts arrays): minimum image,
// overlap, Hertz force of the paper's law, branch between body centres.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "Drivers.hpp"
#include "core/Scene.hpp"
#include "dynamics/ContactDetection.hpp"
#include "dynamics/ContactForces.hpp"

namespace trueaniso::testing {

// Detection and one force evaluation at rest (clumps included; Driver is for single spheres).
inline void evaluateContacts(Scene& s) {
  s.refreshMembers();
  ContactDetection detection;
  detection.skinFactor = 0.5;
  detection.apply(s);
  ContactForces forces;
  forces.apply(s);
}

struct BruteContact {
  int body1, body2;
  Vec3 n, L;
  Real rbar, N;
};

// Every touching member pair of different bodies, brute force O(m^2), minimum image.
inline std::vector<BruteContact> bruteContacts(const Scene& s) {
  std::vector<BruteContact> out;
  const Vec3 h = s.cell.hSize.diagonal();  // orthorhombic scenes
  const Real Estar = s.material.contactModulus();
  const Members& M = s.members;
  for (int i = 0; i < M.size(); ++i)
    for (int j = i + 1; j < M.size(); ++j) {
      if (M.body[i] == M.body[j]) continue;
      Vec3 d = M.pos[j] - M.pos[i];
      Vec3 image;
      for (int k = 0; k < 3; ++k) image[k] = -h[k] * std::round(d[k] / h[k]);
      d += image;
      const Real dist = d.norm(), ri = M.radius[i], rj = M.radius[j];
      const Real delta = ri + rj - dist;
      if (delta <= 0) continue;
      BruteContact c;
      c.body1 = M.body[i];
      c.body2 = M.body[j];
      c.n = d / dist;
      c.L = s.bodies.pos[M.body[j]] + image - s.bodies.pos[M.body[i]];
      c.rbar = 2 * ri * rj / (ri + rj);
      // Hertz with R* = rbar/2 (Johnson's contact mechanics), written independently of the law.
      c.N = 4.0 / 3.0 * Estar * std::sqrt(0.5 * c.rbar) * std::pow(delta, 1.5);
      out.push_back(c);
    }
  return out;
}

// Six spheres of unequal radii with five known contacts: A-B, A-C, B-C (a tilted triangle
// straddling the cell's x boundary, so that contacts go through the periodic image), C-D with D
// pointing away from the triangle, D-F further out; E touches nothing.
// Contacts per particle: A2 B2 C3 D2 E0 F1.
inline std::shared_ptr<Scene> handSpheres() {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real h = 2e-3;
  s->cell.setBox(Vec3::Constant(h));
  const Real rA = 1.0e-4, rB = 1.2e-4, rC = 0.9e-4, rD = 1.1e-4, rE = 1.0e-4, rF = 0.8e-4;
  const Real dAB = rA + rB - 2e-7, dAC = rA + rC - 1e-7, dBC = rB + rC - 3e-7;
  const Real dCD = rC + rD - 1.5e-7, dDF = rD + rF - 0.5e-7;
  const Quat q = Quat(Eigen::AngleAxisd(0.7, Vec3(0.3, -0.5, 0.8).normalized()));
  const Vec3 A(h - 0.1e-3, 1.0e-3, 1.0e-3);
  const Vec3 B = A + q * Vec3(dAB, 0, 0);
  const Real x = (dAB * dAB + dAC * dAC - dBC * dBC) / (2 * dAB);
  const Vec3 C = A + q * Vec3(x, std::sqrt(dAC * dAC - x * x), 0);
  const Vec3 u = (C - 0.5 * (A + B)).normalized();
  const Vec3 D = C + dCD * u;
  const Vec3 F = D + dDF * (u + 0.5 * u.cross(Vec3(0, 0, 1)).normalized()).normalized();
  for (const auto& [p, r] : {std::pair{A, rA}, {B, rB}, {C, rC}, {D, rD}, {Vec3(0.6e-3, 0.4e-3, 1.6e-3), rE}, {F, rF}})
    s->addSphere(p, r);
  return s;
}

inline Real clumpMass(const Material& m, const std::vector<Real>& radii) {
  Real v = 0;
  for (Real r : radii) v += 4.0 / 3.0 * M_PI * r * r * r;
  return m.density * v;  // overlap ignored: any positive mass will do for these tests
}

// Two identical dimers (members at +-d on the body x axis), the second translated by
// (0, 2r - delta, 0): two member contacts between the clumps, both with n = L = e_y direction.
// A sphere touches the first dimer's +d member obliquely, so that its branch vector (from the
// dimer's centre) is not along its normal. Contacts per particle: dimer1 3, dimer2 2, sphere 1.
inline std::shared_ptr<Scene> twoClumps() {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  s->cell.setBox(Vec3::Constant(2e-3));
  const Real r = 1e-4, d = 0.8e-4, r3 = 0.7e-4;
  const std::vector<Vec3> offsets{Vec3(-d, 0, 0), Vec3(d, 0, 0)};
  const std::vector<Real> radii{r, r};
  const Real m = clumpMass(s->material, radii);
  const Vec3 I(0.1 * m * r * r, 0.3 * m * r * r, 0.3 * m * r * r);
  const Vec3 P1(1.0e-3, 1.0e-3, 1.0e-3);
  s->addClump(P1, Quat::Identity(), offsets, radii, m, I);
  s->addClump(P1 + Vec3(0, 2 * r - 3e-7, 0), Quat::Identity(), offsets, radii, m, I);
  s->addSphere(P1 + Vec3(d, 0, 0) + (r + r3 - 2e-7) * Vec3(1, -1, 0.5).normalized(), r3);
  return s;
}

// n spheres (radii 0.8-1.2 r) or dimers placed at random at solid fraction phi, overlaps allowed:
// a dense random network of a few thousand contacts for identities that need many terms.
inline std::shared_ptr<Scene> randomGas(int n, Real phi, unsigned seed, bool dimers = false) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<Real> U(0, 1);
  const Real r = 1e-4;
  std::vector<Real> radii(n);
  Real vol = 0;
  for (Real& x : radii) { x = r * (0.8 + 0.4 * U(gen)); vol += (dimers ? 2 : 1) * 4.0 / 3.0 * M_PI * x * x * x; }
  const Real side = std::cbrt(vol / phi);
  s->cell.setBox(Vec3::Constant(side));
  for (int i = 0; i < n; ++i) {
    const Vec3 p = Vec3(U(gen), U(gen), U(gen)) * side;
    if (!dimers) { s->addSphere(p, radii[i]); continue; }
    const Real x = radii[i];
    const std::vector<Real> rr{x, 0.8 * x};
    const Quat q = Quat(Eigen::AngleAxisd(2 * M_PI * U(gen), Vec3(U(gen) - 0.5, U(gen) - 0.5, U(gen) - 0.5).normalized()));
    s->addClump(p, q, {Vec3(-0.5 * x, 0, 0), Vec3(0.6 * x, 0, 0)}, rr, clumpMass(s->material, rr),
                Vec3::Constant(0.4 * clumpMass(s->material, rr) * x * x));
  }
  return s;
}

}  // namespace trueaniso::testing
