// Micromechanical stiffness (Eqs. 35-37), Appendix A and the moduli of Eqs. (39)-(42), against
// independent routes: the kinematic sum of Eq. (26) contact by contact, the compliance matrix,
// and the simple cubic packing in closed form (section 4.2).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "FabricScenes.hpp"
#include "Lattices.hpp"
#include "dynamics/ContactRefresh.hpp"
#include "contact/HertzMindlin.hpp"
#include "measure/Fabric.hpp"
#include "measure/Stress.hpp"
#include "theory/HertzRange.hpp"
#include "theory/Micromechanics.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

// Eq. (26) with Eq. (27): C_ijkl = (1/V) sum L_i K_jl L_k, K = k_n n n + k_s* (I - n n), the
// stiffnesses of Eqs. (5)-(6) with k_s* = zeta k_s. No fabric tensor involved.
Mat9 kinematicSum(const Scene& s, Real zeta) {
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  Mat9 out = Mat9::Zero();
  for (int c = 0; c < C.size(); ++c) {
    if (!C.active(c)) continue;
    const Vec3& n = C.normal[c];
    const Vec3& L = C.branch(c);
    const Real kn = law.knFromForce(C.normalForce[c], C.rbar[c]);
    const Real ks = zeta * law.ksFromForce(C.normalForce[c], C.rbar[c]);
    const Mat3 K = kn * n * n.transpose() + ks * (Mat3::Identity() - n * n.transpose());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          for (int l = 0; l < 3; ++l) out(3 * i + j, 3 * k + l) += L[i] * K(j, l) * L[k];
  }
  return out / s.cell.volume();
}

Real relErr(const Mat9& a, const Mat9& b) { return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff(); }

// A simple cubic lattice of 4x4x4 equal spheres, spacing a = 2^-12 m (exact in binary, so every
// contact has bit-identical geometry), overlap delta chosen for sigma ~ 100 kPa (N = sigma a^2).
std::shared_ptr<Scene> simpleCubic(Real* spacing, Real* radius) {
  auto s = std::make_shared<Scene>();
  s->material = paperMaterial();
  const Real a = std::ldexp(1.0, -12), sigma = 100e3, Estar = s->material.contactModulus();
  Real delta = 1e-7;
  for (int it = 0; it < 50; ++it) {  // fixed point: N = (4/3) E* sqrt(r/2) delta^1.5, r = (a+delta)/2
    const Real r = 0.5 * (a + delta);
    delta = std::pow(sigma * a * a / (4.0 / 3.0 * Estar * std::sqrt(0.5 * r)), 2.0 / 3.0);
  }
  const Real r = 0.5 * (a + delta);
  s->cell.setBox(Vec3::Constant(4 * a));
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) s->addSphere(Vec3(i, j, k) * a, r);
  *spacing = a;
  *radius = r;
  return s;
}

}  // namespace

// Eq. (35)/(37) is Eq. (26) rewritten with B and M (Eqs. 31-34): equal contact by contact when
// Nc/V is the counted density, for spheres and for clumps (L not along n), with zeta = 1 and
// with the paper's fitted zeta = 0.552. Round-off of sums of ~1e3 terms: 1e-12.
TEST(Micromechanics, Eq37EqualsKinematicSum) {
  for (bool dimers : {false, true}) {
    auto s = randomGas(500, 0.6, 17, dimers);
    evaluateContacts(*s);
    const Fabric f = fabric(*s);
    ASSERT_GT(f.counts.contacts, 300);
    for (Real zeta : {1.0, 0.552}) {
      const Mat9 C = stiffnessTensor(f.B, f.M, f.contactDensityCount(), s->material.Cn(), s->material.Cs(), zeta);
      EXPECT_LT(relErr(C, kinematicSum(*s, zeta)), 1e-12) << "dimers " << dimers << " zeta " << zeta;
    }
  }
}

// The diagonal C_kkkk with zeta = 1 is also what the servo's affine stiffness estimate computes
// from the tangent 1.5 N / delta (Stress.cpp): a second code path for the same number.
TEST(Micromechanics, AxialComponentsEqualAffineStiffness) {
  auto s = randomGas(800, 0.62, 3);
  evaluateContacts(*s);
  const Fabric f = fabric(*s);
  const Mat9 C = stiffnessTensor(f.B, f.M, f.contactDensityCount(), s->material.Cn(), s->material.Cs(), 1.0);
  const Vec6 affine = affineStiffness(*s);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(C(4 * k, 4 * k), affine[k], 1e-12 * affine[k]);
  // The shear components: the minor-symmetrised C_ijij of the engineering shear strain
  // (docs/studies/statics.md, "Eq. (32) and the paper's Appendix A"), (C_ijij + C_jiji + C_ijji + C_jiij) / 4.
  for (int I = 3; I < 6; ++I) {
    const int i = voigt::kRow[I], j = voigt::kCol[I], ij = pairIndex(i, j), ji = pairIndex(j, i);
    const Real minor = 0.25 * (C(ij, ij) + C(ji, ji) + C(ij, ji) + C(ji, ij));
    EXPECT_NEAR(minor, affine[I], 1e-12 * affine[I]) << "Voigt " << I;
  }
}

// Appendix A written out from B and M as printed (A1-A9), against the symmetrisation of the
// full tensor; zeros elsewhere (Eq. 38).
TEST(Micromechanics, AppendixAFromBAndM) {
  auto s = randomGas(500, 0.6, 23, true);
  evaluateContacts(*s);
  const Fabric f = fabric(*s);
  const Real nv = f.contactDensityEq36(), Cn = s->material.Cn(), zeta = 0.7, Cs = zeta * s->material.Cs();
  const Mat6 V = orthotropicStiffness(stiffnessTensor(f.B, f.M, nv, Cn, s->material.Cs(), zeta));
  auto M = [&](int i, int j, int k, int l) { return f.M4(i - 1, j - 1, k - 1, l - 1); };
  auto B = [&](int i, int j) { return f.B(i - 1, j - 1); };
  Mat6 A = Mat6::Zero();
  A(0, 0) = nv * (Cs * B(1, 1) + (Cn - Cs) * M(1, 1, 1, 1));
  A(1, 1) = nv * (Cs * B(2, 2) + (Cn - Cs) * M(2, 2, 2, 2));
  A(2, 2) = nv * (Cs * B(3, 3) + (Cn - Cs) * M(3, 3, 3, 3));
  A(0, 1) = A(1, 0) = nv / 2 * (Cn - Cs) * (M(1, 1, 2, 2) + M(2, 2, 1, 1));
  A(0, 2) = A(2, 0) = nv / 2 * (Cn - Cs) * (M(1, 1, 3, 3) + M(3, 3, 1, 1));
  A(1, 2) = A(2, 1) = nv / 2 * (Cn - Cs) * (M(2, 2, 3, 3) + M(3, 3, 2, 2));
  A(3, 3) = nv / 2 * (Cs * (B(2, 2) + B(3, 3)) + (Cn - Cs) * (M(2, 3, 2, 3) + M(3, 2, 3, 2)));
  A(4, 4) = nv / 2 * (Cs * (B(1, 1) + B(3, 3)) + (Cn - Cs) * (M(1, 3, 1, 3) + M(3, 1, 3, 1)));
  A(5, 5) = nv / 2 * (Cs * (B(1, 1) + B(2, 2)) + (Cn - Cs) * (M(1, 2, 1, 2) + M(2, 1, 2, 1)));
  EXPECT_LT((V - A).cwiseAbs().maxCoeff(), 1e-13 * A.cwiseAbs().maxCoeff());
}

// Eqs. (39)-(42) against the compliance S = C^-1 of a generic orthotropic matrix (from a random
// clump network, so no two moduli coincide): E_i = 1/S_ii, nu_ij = -S_ji/S_ii, G = 1/S_44.. .
// LU inverse of a well-conditioned 6x6: ~1e-15 relative; 1e-12 leaves margin.
TEST(Orthotropic, ModuliEqualCompliance) {
  auto s = randomGas(400, 0.6, 31, true);
  evaluateContacts(*s);
  const MicromechanicalPrediction p = predict(fabric(*s), s->material, 0.552);
  const Mat6 S = p.voigt.inverse();
  const OrthotropicModuli& m = p.moduli;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(m.E[i], 1 / S(i, i), 1e-12 * m.E[i]);
    EXPECT_NEAR(m.G[i], 1 / S(3 + i, 3 + i), 1e-12 * m.G[i]);
    for (int j = 0; j < 3; ++j) {
      if (i == j) { EXPECT_TRUE(std::isnan(m.nu(i, i))); continue; }
      EXPECT_NEAR(m.nu(i, j), -S(j, i) / S(i, i), 1e-12);
      EXPECT_NEAR(m.nu(i, j) / m.E[i], m.nu(j, i) / m.E[j], 1e-12 / m.E[i]);  // reciprocity
    }
  }
  const Real det = p.voigt.topLeftCorner<3, 3>().determinant();
  EXPECT_NEAR(m.Delta, det, 1e-12 * m.Delta);  // Eq. (41)
  EXPECT_GT(std::abs(m.nu(0, 1) - m.nu(1, 0)), 1e-4);  // a generic matrix: the test has teeth
}

// Eqs. (40)-(42) as printed (cofactors of the normal block; the last line corrected) on a symmetric
// block: the inverse the code takes is the same thing. Round-off only: 1e-12.
TEST(Orthotropic, ClosedFormsOfEqs40to42OnASymmetricBlock) {
  Mat6 C = Mat6::Zero();
  C.topLeftCorner<3, 3>() << 500, 120, 90, 120, 420, 70, 90, 70, 610;
  C(3, 3) = 150; C(4, 4) = 170; C(5, 5) = 160;
  const Real c11 = C(0, 0), c22 = C(1, 1), c33 = C(2, 2), c12 = C(0, 1), c13 = C(0, 2), c23 = C(1, 2);
  const Real Delta = c11 * c22 * c33 + 2 * c12 * c13 * c23 - c11 * c23 * c23 - c22 * c13 * c13 - c33 * c12 * c12;
  const Real a11 = c22 * c33 - c23 * c23, a22 = c11 * c33 - c13 * c13, a33 = c11 * c22 - c12 * c12;
  const OrthotropicModuli m = orthotropicModuli(C);
  EXPECT_NEAR(m.Delta, Delta, 1e-12 * Delta);
  EXPECT_NEAR(m.E[0], Delta / a11, 1e-12 * m.E[0]);
  EXPECT_NEAR(m.E[1], Delta / a22, 1e-12 * m.E[1]);
  EXPECT_NEAR(m.E[2], Delta / a33, 1e-12 * m.E[2]);
  EXPECT_NEAR(m.nu(0, 1), (c12 * c33 - c13 * c23) / a11, 1e-12);
  EXPECT_NEAR(m.nu(0, 2), (c13 * c22 - c12 * c23) / a11, 1e-12);
  EXPECT_NEAR(m.nu(1, 0), (c12 * c33 - c13 * c23) / a22, 1e-12);
  EXPECT_NEAR(m.nu(1, 2), (c23 * c11 - c12 * c13) / a22, 1e-12);
  EXPECT_NEAR(m.nu(2, 0), (c13 * c22 - c12 * c23) / a33, 1e-12);
  EXPECT_NEAR(m.nu(2, 1), (c23 * c11 - c12 * c13) / a33, 1e-12);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(m.G[i], C(3 + i, 3 + i));
}

// A prestressed tangent is not symmetric. The moduli are the probe's: a stress increment on x alone
// (the other normal stresses held, no shear strain) gives strains S e_x, whence E_x = 1/S_xx and
// nu_xj = -S_jx/S_xx, which the symmetric closed forms would miss.
TEST(Orthotropic, NonSymmetricBlockGivesTheProbeModuli) {
  Mat6 C = Mat6::Zero();
  C.topLeftCorner<3, 3>() << 500, 140, 90, 100, 420, 85, 95, 60, 610;
  C(3, 3) = 150; C(4, 4) = 170; C(5, 5) = 160;
  const OrthotropicModuli m = orthotropicModuli(C);
  for (int i = 0; i < 3; ++i) {
    Vec3 dsigma = Vec3::Zero();
    dsigma[i] = 1.0;
    const Vec3 deps = C.topLeftCorner<3, 3>().fullPivLu().solve(dsigma);  // a second solver
    EXPECT_NEAR(m.E[i], 1.0 / deps[i], 1e-12 * m.E[i]);
    for (int j = 0; j < 3; ++j)
      if (j != i) EXPECT_NEAR(m.nu(i, j), -deps[j] / deps[i], 1e-12);
  }
  EXPECT_GT(std::abs(m.nu(0, 1) / m.E[0] - m.nu(1, 0) / m.E[1]) * m.E[0], 1e-2);  // not reciprocal: teeth
}

// The printed last line of Eq. (42), "nu_xy = (C23 C11 - C12 C23)/(C11 C22 - C12^2)", is not a
// Poisson's ratio of the compliance: its label repeats nu_xy and its numerator should read
// C23 C11 - C12 C13 (nu_zy). Shown on a generic matrix.
TEST(Orthotropic, PrintedLastLineOfEq42IsAMisprint) {
  Mat6 C = Mat6::Zero();
  C.topLeftCorner<3, 3>() << 500, 120, 90, 120, 420, 70, 90, 70, 610;
  C(3, 3) = 150; C(4, 4) = 170; C(5, 5) = 160;
  const Mat6 S = C.inverse();
  const OrthotropicModuli m = orthotropicModuli(C);
  const Real printed = (C(1, 2) * C(0, 0) - C(0, 1) * C(1, 2)) / (C(0, 0) * C(1, 1) - C(0, 1) * C(0, 1));
  const Real nuzy = -S(1, 2) / S(2, 2);
  EXPECT_NEAR(m.nu(2, 1), nuzy, 1e-14);
  EXPECT_GT(std::abs(printed - nuzy), 1e-3);
  EXPECT_GT(std::abs(printed - m.nu(0, 1)), 1e-3);
}

// Section 4.2: an equal-sized simple cubic packing with zeta = 1. Each sphere has 6 contacts,
// L = a n along the axes, Nc/V = 3/a^3 by either route, so C11 = (3/a^3) C_n w a^2/3 = k_n/a
// (w = (r N)^(1/3)) and C12 = 0: E = k_n / a exactly (k_n / 2r only to O(delta/r)), nu_ij = 0,
// G = k_s / a. With sigma = N / a^2 (Love-Weber), E = (3 E*^2 sigma r / a)^(1/3), which is the
// design note's (12 E*^2 sigma)^(1/3) / 2 ~ 406.7 MPa when a = 2r.
TEST(Micromechanics, SimpleCubicPackingInClosedForm) {
  Real a, r;
  auto s = simpleCubic(&a, &r);
  evaluateContacts(*s);
  const Fabric f = fabric(*s);
  ASSERT_EQ(f.counts.contacts, 192);
  ASSERT_EQ(f.Zm, 6.0);
  const Contacts& C = s->contacts;
  int first = -1;
  for (int c = 0; c < C.size(); ++c)
    if (C.active(c)) { first = c; break; }
  // the force law's own tangent 1.5 N/delta, not Eq. (5): an independent route to k_n
  const Real kn = HertzMindlin::normalStiffness(C.normalForce[first], C.overlap[first]);
  const Real ks = s->material.stiffnessRatio() * kn;
  const Mat3 sigma = loveWeberStress(*s);
  const Real Estar = s->material.contactModulus();
  for (auto density : {ContactDensity::Eq36, ContactDensity::Count}) {
    const MicromechanicalPrediction p = predict(f, s->material, 1.0, density);
    EXPECT_NEAR(p.contactDensity, 3 / (a * a * a), 1e-13 * p.contactDensity);
    for (int i = 0; i < 3; ++i) {
      // Eq. (5) and 1.5 N/delta agree to round-off of cbrt and of the Hertz power: 1e-12.
      EXPECT_NEAR(p.moduli.E[i], kn / a, 1e-12 * kn / a);
      EXPECT_NEAR(p.moduli.E[i], std::cbrt(3 * Estar * Estar * sigma(i, i) * r / a), 1e-12 * p.moduli.E[i]);
      EXPECT_NEAR(p.moduli.G[i], ks / a, 1e-12 * ks / a);
      for (int j = 0; j < 3; ++j)
        if (i != j) EXPECT_EQ(p.moduli.nu(i, j), 0.0);  // off-axis branch components are exact zeros
    }
    // the design note's reference value at 100 kPa; a/2r = 1 - delta/2r ~ 1 - 3e-4
    EXPECT_NEAR(p.moduli.E[0], 406.7e6, 1e-3 * 406.7e6);
  }
}

// One range for zeta everywhere (ZetaRange): a fit that lands above 1 (rotations blocked: 1.01)
// can still be predicted with; below 0 or beyond the range is refused.
TEST(Micromechanics, RefusesZetaOutsideItsRange) {
  auto s = handSpheres();
  evaluateContacts(*s);
  const Fabric f = fabric(*s);
  EXPECT_THROW(predict(f, s->material, -0.1), InputError);
  EXPECT_THROW(predict(f, s->material, ZetaRange::hi + 0.5), InputError);
  EXPECT_THROW(predict(f, s->material, std::nan("")), InputError);
  EXPECT_NO_THROW(predict(f, s->material, 0.0));
  EXPECT_NO_THROW(predict(f, s->material, 1.01));
}

// The overlap estimate against an FCC lattice, where every contact carries one force: its stress
// (Love-Weber, from the code's forces) put into the estimate gives back the lattice's overlap.
// The estimate takes the branch length as 2R, the lattice's is 2R - delta, so its stress is that
// of the estimate times (1 - delta/2R); with that factor the two agree to rounding.
TEST(HertzRange, OverlapOfAnFccLatticeFromItsStress) {
  for (Real delta : {4e-7, 4e-6}) {
    auto s = fcc(2, delta);
    refreshContacts(*s);
    const Real p = loveWeberStress(*s).trace() / 3.0;
    const Real phi = s->bodies.size() * 4.0 / 3.0 * 3.14159265358979323846 * kR * kR * kR / s->cell.volume();
    const Real ratio = hertzOverlapRatio(s->material, p / (1.0 - delta / (2 * kR)), phi, 12.0);
    EXPECT_NEAR(ratio / (delta / kR), 1.0, 1e-10) << "delta " << delta;
    EXPECT_LT(hertzOverlapRatio(s->material, p, phi, 12.0), ratio);  // without the factor: less
  }
  const Material m = paperMaterial();
  // The scripts' bound for the paper's material in a dense packing: about 67 MPa (docs/runs.md).
  EXPECT_NEAR(hertzOverlapRatio(m, 67e6, 0.633, 5.97), kMaxOverlapRatio, 0.001);
  EXPECT_THROW(hertzOverlapRatio(m, -1.0, 0.6, 6.0), InputError);
  EXPECT_THROW(hertzOverlapRatio(m, 1e5, 1.0, 6.0), InputError);
  EXPECT_THROW(hertzOverlapRatio(m, 1e5, 0.6, 0.0), InputError);
}
