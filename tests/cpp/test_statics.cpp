// Static stiffness of the contact network: the linearised contact law against finite
// differences of the dynamic force loop; the assembled network tangent against finite differences
// of every body's resultant; lattices against closed-form elastic constants (simple cubic, cubic
// and orthorhombic, rotations free and blocked; FCC); the sparse solve against a dense one;
// rattlers, zero modes and out-of-balance states; and the relaxed stiffness against the strain
// increments of a dynamic relaxation with sliding suppressed.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "Drivers.hpp"
#include "Lattices.hpp"
#include "dynamics/NewtonIntegrator.hpp"
#include "dynamics/Simulation.hpp"
#include "dynamics/TimeStepper.hpp"
#include "measure/Stress.hpp"
#include "statics/ContactTangent.hpp"
#include "statics/HeldState.hpp"
#include "statics/NetworkMatrix.hpp"
#include "statics/Rattlers.hpp"
#include "statics/RotationFactor.hpp"
#include "statics/StaticStiffness.hpp"

using namespace trueaniso;
using namespace trueaniso::testing;

namespace {

Real relativeError(const Mat6& a, const Mat6& b) { return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff(); }

// ---- finite differences of the dynamic force loop -------------------------------------------

struct Response {
  Eigen::VectorXd R;  // [F_0, T_0, F_1, T_1, ...] over bodies
  Vec6 sigmaV;        // Voigt of the symmetric part of sum F (x) L
};

// One step of the dynamics' kinematics from a held state: body velocities q/h, the cell's
// diagonal strain rate e/h, positions moved as NewtonIntegrator does, then the force loop.
Response respond(const Scene& held, const Eigen::VectorXd& q, const Vec3& e, Real h) {
  Scene s = held;
  s.dt = h;
  s.blockRotations = false;
  s.cell.velGrad = e.asDiagonal();
  const Vec3 stretch = Vec3::Ones() + h * e;
  for (int b = 0; b < s.bodies.size(); ++b) {
    s.bodies.vel[b] = q.segment<3>(6 * b);
    s.bodies.angVel[b] = q.segment<3>(6 * b + 3);
    s.bodies.pos[b] = s.bodies.pos[b].cwiseProduct(stretch) + h * s.bodies.vel[b];
    const Vec3 w = s.bodies.angVel[b];
    if (w.norm() > 0)
      s.bodies.orientation[b] = (Quat(Eigen::AngleAxisd(w.norm() * h, w.normalized())) * s.bodies.orientation[b]).normalized();
  }
  s.cell.hSize = stretch.asDiagonal() * s.cell.hSize;
  s.refreshMembers();
  ContactForces().apply(s);
  Response r;
  r.R.resize(6 * s.bodies.size());
  for (int b = 0; b < s.bodies.size(); ++b) {
    r.R.segment<3>(6 * b) = s.bodies.force[b];
    r.R.segment<3>(6 * b + 3) = s.bodies.torque[b];
  }
  r.sigmaV = voigt::fromTensor(loveWeberStress(s) * s.cell.volume());
  return r;
}

// Central difference of the response to the increment (q, e): its error is O(h^2), the even
// orders of the one-step update (new k_s, new projection) cancel.
Response centralDifference(const Scene& held, const Eigen::VectorXd& q, const Vec3& e, Real h) {
  const Response p = respond(held, q, e, h), m = respond(held, -q, -e, h);
  return {(p.R - m.R) / (2 * h), (p.sigmaV - m.sigmaV) / (2 * h)};
}

// Gives every contact of a held state a tangential force of random direction, |Fs| <= 0.3 N,
// so that the frame-rotation, twist and lever-arm terms are exercised.
void randomShearForces(Scene& held, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<Real> Nd(0, 1);
  Contacts& C = held.contacts;
  for (int c = 0; c < C.size(); ++c) {
    if (!C.active(c)) continue;
    Vec3 t(Nd(gen), Nd(gen), Nd(gen));
    t -= C.normal[c].dot(t) * C.normal[c];
    C.shearForce[c] = 0.3 * C.normalForce[c] * t.normalized();
  }
}

Eigen::VectorXd randomIncrement(int bodies, Real length, Real angle, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<Real> Nd(0, 1);
  Eigen::VectorXd q(6 * bodies);
  for (int b = 0; b < bodies; ++b)
    for (int k = 0; k < 6; ++k) q[6 * b + k] = (k < 3 ? length : angle) * Nd(gen);
  return q;
}

// A held two-body scene, spheres or clumps, touching across the periodic boundary.
Scene heldPair(bool clumps) {
  Scene s;
  s.material = paperMaterial();
  s.cell.setBox(Vec3(8, 9, 10) * kR);
  const Vec3 c1(0.5 * kR, 4 * kR, 5 * kR);
  Vec3 dir = Vec3(-1.0, 0.3, -0.2).normalized();  // body 2 sits across x = 0, in the image
  if (!clumps) {
    // Radii r and 0.9 r, overlap 2e-6 = 0.02 r (large, so that the initial-force terms are
    // well above the finite differences' error).
    s.addSphere(c1, kR);
    s.addSphere(c1 + (1.9 * kR - 2e-6) * dir + Vec3(s.cell.hSize(0, 0), 0, 0), 0.9 * kR);
  } else {
    // Two 2-member clumps; member radii r and 0.7 r, offsets along the clump axis.
    const std::vector<Vec3> off = {Vec3(0.5 * kR, 0, 0), Vec3(-0.6 * kR, 0, 0)};
    const std::vector<Real> rad = {kR, 0.7 * kR};
    const Quat q1(Eigen::AngleAxisd(0.4, Vec3(0.2, 1, 0.3).normalized()));
    const Quat q2(Eigen::AngleAxisd(1.1, Vec3(1, -0.4, 0.7).normalized()));
    s.addClump(c1, q1, off, rad, 1e-9, Vec3(1e-17, 2e-17, 2e-17));
    // Put clump 2's first member in contact with clump 1's first member.
    const Vec3 m1 = c1 + q1 * off[0];
    const Vec3 m2 = m1 + (2 * kR - 2e-6) * dir;
    s.addClump(m2 - q2 * off[0] + Vec3(s.cell.hSize(0, 0), 0, 0), q2, off, rad, 1e-9, Vec3(1e-17, 2e-17, 2e-17));
  }
  s.refreshMembers();
  return heldState(s);
}

}  // namespace

// ---- the contact tangent against the dynamic law ---------------------------------------------

// J q + JE e and the stress rows of one contact, spheres and clumps, with a shear force of 0.3 N,
// against central differences of ContactForces. Tolerance 1e-6 of the largest component: the
// difference's truncation is ~(h q / delta)^2 ~ 1e-12 and its round-off ~1e-16 N / (h k delta)
// ~ 1e-10; a missing initial-force term (size ~ delta / l ~ 1e-2 of the k_n terms here, where
// the overlaps are ~1e-2 r) would show at ~1e-2.
TEST(ContactTangent, MatchesFiniteDifferencesOfTheDynamicLaw) {
  for (bool clumps : {false, true}) {
    Scene held = heldPair(clumps);
    int active = 0;
    for (int c = 0; c < held.contacts.size(); ++c) active += held.contacts.active(c);
    ASSERT_GE(active, 1) << "clumps=" << clumps;
    randomShearForces(held, 5);
    const Real delta = 2e-6, h = 1e-6;
    for (unsigned seed = 1; seed <= 3; ++seed) {
      const Eigen::VectorXd q = randomIncrement(2, delta, delta / kR, seed);
      std::mt19937_64 gen(seed + 10);
      std::normal_distribution<Real> Nd(0, 1);
      const Vec3 e = Vec3(Nd(gen), Nd(gen), Nd(gen)) * delta / kR;
      const Response fd = centralDifference(held, q, e, h);
      Eigen::VectorXd Jq = Eigen::VectorXd::Zero(12);
      Vec6 dSigma = Vec6::Zero();
      Vec6 ev;
      ev << e, 0, 0, 0;
      for (int c = 0; c < held.contacts.size(); ++c) {
        if (!held.contacts.active(c)) continue;
        const ContactTangent t = linearise(heldContact(held, c));
        Eigen::Matrix<Real, 12, 1> qc;
        const int a = held.contacts.b1[c], b = held.contacts.b2[c];
        qc << q.segment<6>(6 * a), q.segment<6>(6 * b);
        const Eigen::Matrix<Real, 12, 1> dR = t.J * qc + t.JE * ev;
        Jq.segment<6>(6 * a) += dR.head<6>();
        Jq.segment<6>(6 * b) += dR.tail<6>();
        dSigma += t.S * qc + (t.SEnormal + t.SEshear + t.SEgeometric) * ev;
      }
      // Forces and torques compared with their own scales (torque / lever arm ~ force).
      for (int b = 0; b < 2; ++b) {
        const Real fs = Jq.segment<3>(6 * b).norm(), ts = Jq.segment<3>(6 * b + 3).norm();
        EXPECT_LT((Jq.segment<3>(6 * b) - fd.R.segment<3>(6 * b)).norm(), 1e-6 * fs) << "clumps=" << clumps;
        EXPECT_LT((Jq.segment<3>(6 * b + 3) - fd.R.segment<3>(6 * b + 3)).norm(), 1e-6 * ts) << "clumps=" << clumps;
      }
      EXPECT_LT((dSigma - fd.sigmaV).norm(), 1e-6 * dSigma.norm()) << "clumps=" << clumps;
    }
  }
}

// Balance of the pair itself, an identity of the law that the linearisation must keep: the two
// forces are opposite (F_a = -F_b) and the two moments about the body centres satisfy
// T_a + T_b = F x L (both act at one contact point, L = x_b + image - x_a), so
// d(T_a + T_b) = dF x L + F x dL for every increment. This checks the lever-arm terms (arms of
// r - delta/2 along n, offsets of clump members) against the branch terms. Tolerance: round-off.
TEST(ContactTangent, PairMomentBalance) {
  Scene held = heldPair(true);
  randomShearForces(held, 9);
  int checked = 0;
  for (int c = 0; c < held.contacts.size(); ++c) {
    if (!held.contacts.active(c)) continue;
    const HeldContact h = heldContact(held, c);
    const ContactTangent t = linearise(h);
    const Vec3 F = h.normalForce * h.normal + h.shearForce;
    for (int k = 0; k < 18; ++k) {  // 12 body DOFs, then 6 strains
      Vec3 dFa, dFb, dTsum, dL;
      if (k < 12) {
        dFa = t.J.block<3, 1>(0, k); dFb = t.J.block<3, 1>(6, k);
        dTsum = t.J.block<3, 1>(3, k) + t.J.block<3, 1>(9, k);
        dL = Vec3::Zero();
        if (k >= 6 && k < 9) dL[k - 6] = 1;
        if (k < 3) dL[k] = -1;
      } else {
        dFa = t.JE.block<3, 1>(0, k - 12); dFb = t.JE.block<3, 1>(6, k - 12);
        dTsum = t.JE.block<3, 1>(3, k - 12) + t.JE.block<3, 1>(9, k - 12);
        dL = voigt::branchMap(h.branch).col(k - 12);
      }
      const Real scale = dFb.norm() * h.branch.norm() + F.norm() * dL.norm();
      EXPECT_LT((dFa + dFb).norm(), 1e-14 * dFb.norm() + 1e-300);
      EXPECT_LT((dTsum - (dFb.cross(h.branch) + F.cross(dL))).norm(), 1e-12 * scale) << "column " << k;
    }
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

// ---- the assembled network against the dynamic law -------------------------------------------

// A jittered simple cubic lattice with random shear forces (no rattler: 6 contacts per sphere):
// the assembled K and JE give every body's force and moment increments of the dynamic loop.
// Same tolerance argument as above.
TEST(NetworkMatrix, MatchesFiniteDifferencesOfAllBodies) {
  auto s = simpleCubic(3, Vec3(4e-6, 3e-6, 5e-6));
  std::mt19937_64 gen(2);
  std::normal_distribution<Real> Nd(0, 1);
  for (Vec3& p : s->bodies.pos) p += 2e-7 * Vec3(Nd(gen), Nd(gen), Nd(gen));
  s->refreshMembers();
  Scene held = heldState(*s);
  randomShearForces(held, 3);
  const std::vector<char> rattler = findRattlers(held);
  for (char r : rattler) ASSERT_FALSE(r);
  const NetworkMatrix net = assembleNetwork(held, rattler, true);
  const int nb = held.bodies.size();
  ASSERT_EQ(net.size(), 6 * nb);
  const Real h = 1e-6;
  const Eigen::VectorXd q = randomIncrement(nb, 4e-6, 4e-6 / kR, 7);
  const Vec3 e = Vec3(1.0, -0.5, 0.7) * 4e-6 / kR;
  const Response fd = centralDifference(held, q, e, h);
  // The matrix works on scaled rotations s theta and moment equations divided by s.
  Eigen::VectorXd qs = q, fdScaled = fd.R;
  for (int b = 0; b < nb; ++b) {
    qs.segment<3>(6 * b + 3) *= net.rotationScale[b];
    fdScaled.segment<3>(6 * b + 3) /= net.rotationScale[b];
  }
  Vec6 ev;
  ev << e, 0, 0, 0;
  const Eigen::VectorXd model = -(net.K * qs) + net.JE * ev;
  EXPECT_LT((model - fdScaled).cwiseAbs().maxCoeff(), 1e-6 * model.cwiseAbs().maxCoeff());
  const Vec6 dSigma = net.S * qs + net.SE * ev;
  EXPECT_LT((dSigma - fd.sigmaV).norm(), 1e-6 * dSigma.norm());
}

// ---- lattices in closed form ------------------------------------------------------------------

// Simple cubic 4^3, 100-kPa-like overlap, rotations blocked and free: C in closed form (E = C_11
// - ... with C_11 = k_n/a, C_12 = sigma, C_44 = k_s/(2a) - sigma). Tolerance 1e-9: the closed form
// and the solve differ by round-off of sums over ~200 contacts (the brief's 1e-6 is looser).
TEST(StaticStiffness, SimpleCubicClosedForm) {
  const Real delta = 5e-7;
  auto s = simpleCubic(4, Vec3::Constant(delta));
  for (bool rot : {false, true}) {
    StaticStiffness st;
    st.rotations = rot;
    const StaticStiffnessResult r = st.compute(*s);
    const Mat6 C = simpleCubicStiffness(s->material, Vec3::Constant(delta), rot);
    EXPECT_LT(relativeError(r.C, C), 1e-9) << "rotations=" << rot << "\n" << r.C << "\n\n" << C;
    EXPECT_LT(relativeError(r.affine, simpleCubicStiffness(s->material, Vec3::Constant(delta), false)), 1e-9);
    // E = k_n/a of DESIGN.md section 5, corrected by the prestress to second order only.
    const ContactLaw c = law(s->material, delta);
    const Real a = 2 * kR - delta, sig = c.N / (a * a);
    const Real C11 = c.kn / a;
    const Real E = (C11 - sig) * (C11 + 2 * sig) / (C11 + sig);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(r.constants.E[i] / E, 1.0, 1e-9);
      EXPECT_NEAR(r.constants.E[i] / C11, 1.0, 1e-5);  // E = k_n / a to O((sigma a / k_n)^2)
      EXPECT_NEAR(r.constants.G[i] / (c.ks / (2 * a) - sig), 1.0, 1e-9);
    }
    EXPECT_NEAR(r.constants.nu(0, 1), sig / (C11 + sig), 1e-12);  // ~1e-3: the prestress alone
    EXPECT_LT(r.residual, 1e-10);
    EXPECT_LT(r.pinnedReaction, 1e-10);  // the pinned modes are exact zero modes
    EXPECT_TRUE(r.rattlers.empty());
    // Zero modes: the global translation, and with rotations free the counter-rotating rows:
    // theta_x(i, j, k) = f(i) (-1)^(j+k) and its two permutations, 4 per axis on a 4^3 lattice.
    EXPECT_EQ(r.pinned.size(), rot ? 15u : 3u);
  }
}

// Orthorhombic simple cubic with a weak axis: overlaps 1e-6 r along z against 5e-3 r along x
// (stress ratio sigma_x/sigma_z ~ 3e5, stiffness ratio ~70) and rotations free: the shear moduli
// are the series combination of the two shear springs (uniform rotation, moment balance), a
// genuinely non-affine answer, and the matrix carries 12 zero modes. Tolerance 1e-8: the
// conditioning (k ratio ~70) costs about two digits over the cubic case.
TEST(StaticStiffness, OrthorhombicSimpleCubicWithAWeakAxis) {
  const Vec3 delta(5e-7, 2e-7, 1e-10);
  auto s = simpleCubic(4, delta);
  for (bool rot : {false, true}) {
    StaticStiffness st;
    st.rotations = rot;
    const StaticStiffnessResult r = st.compute(*s);
    const Mat6 C = simpleCubicStiffness(s->material, delta, rot);
    EXPECT_LT(relativeError(r.C, C), 1e-8) << "rotations=" << rot << "\n" << r.C << "\n\n" << C;
    // The anisotropic prestress makes the Cauchy tangent non-symmetric (C_xz = sigma_x != C_zx).
    EXPECT_GT(std::abs(r.C(0, 2) - r.C(2, 0)), 0.5 * std::abs(r.C(0, 2)));
    EXPECT_LT(r.residual, 1e-10);
  }
  // Freeing the rotations softens the shear moduli strictly (series < arithmetic mean of springs).
  StaticStiffness free, blocked;
  blocked.rotations = false;
  const Vec3 Gf = free.compute(*s).constants.G, Gb = blocked.compute(*s).constants.G;
  for (int i = 0; i < 3; ++i) EXPECT_LT(Gf[i], 0.99 * Gb[i]);
}

// FCC 3^3 conventional cells at uniform overlap: every sphere is an inversion centre and the
// contact set is cubic, so neither translations nor rotations relax; C in closed form with its
// prestress terms (C_11 = sqrt2/l (k_n + k_s - N/l), C_12 = sqrt2/l ((k_n - k_s)/2 + 5N/(2l)),
// C_44 = sqrt2/l ((k_n + k_s)/2 - 3N/(2l))). Tolerance as for the simple cubic lattice.
TEST(StaticStiffness, FaceCentredCubicClosedForm) {
  const Real delta = 4e-7;
  auto s = fcc(3, delta);
  const Mat6 C = fccStiffness(s->material, delta);
  for (bool rot : {false, true}) {
    StaticStiffness st;
    st.rotations = rot;
    const StaticStiffnessResult r = st.compute(*s);
    EXPECT_LT(relativeError(r.C, C), 1e-9) << "rotations=" << rot << "\n" << r.C << "\n\n" << C;
    EXPECT_LT(relativeError(r.affine, C), 1e-9);
    const Real E = (C(0, 0) - C(0, 1)) * (C(0, 0) + 2 * C(0, 1)) / (C(0, 0) + C(0, 1));
    const Real nu = C(0, 1) / (C(0, 0) + C(0, 1));
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(r.constants.E[i] / E, 1.0, 1e-9);
      EXPECT_NEAR(r.constants.nu(i, (i + 1) % 3), nu, 1e-9);
    }
    EXPECT_EQ(r.pinned.size(), 3u);  // only the global translation
  }
}

// The affine stiffness is Eq. (32) exactly in its normal + shear parts: sum over contacts of
// L_i K_jl L_k, symmetrised, computed here directly from the contact list.
TEST(StaticStiffness, AffinePartIsEquation32) {
  auto s = simpleCubic(3, Vec3(5e-7, 4e-7, 6e-7));  // ~100 kPa overlaps
  std::mt19937_64 gen(4);
  std::normal_distribution<Real> Nd(0, 1);
  for (Vec3& p : s->bodies.pos) p += 3e-8 * Vec3(Nd(gen), Nd(gen), Nd(gen));
  s->refreshMembers();
  const Scene held = heldState(*s);
  StaticStiffness st;
  st.maxUnbalanced = 10;  // a jittered lattice is out of balance; the affine part does not care
  const StaticStiffnessResult r = st.compute(*s);
  // C_ijkl = (1/V) sum L_i K_jl L_k; Voigt entry (I, J) = C_(ij)(kl) symmetrised over i<->j, k<->l.
  const Real ratio = held.material.stiffnessRatio();
  Eigen::Matrix<Real, 81, 1> c = Eigen::Matrix<Real, 81, 1>::Zero();
  for (int q = 0; q < held.contacts.size(); ++q) {
    if (!held.contacts.active(q)) continue;
    const Vec3 n = held.contacts.normal[q], L = held.contacts.branch(q);
    const Real kn = held.material.Cn() * std::cbrt(held.contacts.rbar[q] * held.contacts.normalForce[q]);
    const Mat3 K = kn * n * n.transpose() + ratio * kn * (Mat3::Identity() - n * n.transpose());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          for (int l = 0; l < 3; ++l) c[27 * i + 9 * j + 3 * k + l] += L[i] * K(j, l) * L[k];
  }
  c /= held.cell.volume();
  auto Cijkl = [&](int i, int j, int k, int l) { return c[27 * i + 9 * j + 3 * k + l]; };
  Mat6 eq32;
  for (int I = 0; I < 6; ++I)
    for (int J = 0; J < 6; ++J) {
      const int i = voigt::kRow[I], j = voigt::kCol[I], k = voigt::kRow[J], l = voigt::kCol[J];
      eq32(I, J) = 0.25 * (Cijkl(i, j, k, l) + Cijkl(j, i, k, l) + Cijkl(i, j, l, k) + Cijkl(j, i, l, k));
    }
  // Tolerance 1e-12: k_n = 1.5 N/delta in the code, C_n (rbar N)^(1/3) here, equal to round-off.
  EXPECT_LT(relativeError(r.affineNormal + r.affineShear, eq32), 1e-12);
  // The geometric terms are separate and small: ~ sigma / C_11 ~ 3e-4 at these overlaps.
  EXPECT_LT(r.affineGeometric.cwiseAbs().maxCoeff(), 1e-2 * eq32.cwiseAbs().maxCoeff());
  EXPECT_GT(r.affineGeometric.cwiseAbs().maxCoeff(), 1e-5 * eq32.cwiseAbs().maxCoeff());
}

// ---- rattlers, zero modes, refusal ------------------------------------------------------------

// A free sphere in a void of the lattice, and one touching a single lattice sphere, are rattlers:
// reported, removed, and the relaxed stiffness is that of the lattice (exactly for the free one;
// for the one-contact sphere to its force's share of the stress, ~1e-6 here).
TEST(StaticStiffness, RattlersAreRemovedAndReported) {
  const Real delta = 5e-7;
  auto s = simpleCubic(4, Vec3::Constant(delta));
  StaticStiffness st;
  const StaticStiffnessResult ref = st.compute(*s);
  const Real a = 2 * kR - delta;
  s->addSphere(Vec3(1, 1, 1) * a, 0.3 * kR);  // centre of a cube of 8 spheres: gap 0.87a - 1.3r
  const StaticStiffnessResult r1 = st.compute(*s);
  ASSERT_EQ(r1.rattlers, std::vector<int>{64});
  EXPECT_LT(relativeError(r1.C, ref.C), 1e-13);
  // A second small sphere touching the lattice sphere at (0.5, 0.5, 0.5) a with a tiny overlap.
  const Vec3 p0 = Vec3::Constant(0.5 * a), dir = Vec3(1, 1, 1).normalized();
  s->addSphere(p0 + (1.2 * kR - 1e-10) * dir, 0.2 * kR);
  const StaticStiffnessResult r2 = st.compute(*s);
  ASSERT_EQ(r2.rattlers, (std::vector<int>{64, 65}));
  EXPECT_LT(relativeError(r2.C, ref.C), 1e-5);
}

// A state out of balance is refused before any solve, with a message naming the criterion.
TEST(StaticStiffness, RefusesAStateOutOfBalance) {
  auto s = simpleCubic(4, Vec3::Constant(5e-7));
  s->bodies.pos[5] += Vec3(2e-7, 0, 0);  // 0.4 delta: its two x contacts differ by ~50%
  s->refreshMembers();
  StaticStiffness st;
  try {
    st.compute(*s);
    FAIL() << "an unbalanced state was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("out of force balance"), std::string::npos) << e.what();
  }
  st.maxUnbalanced = 1.0;  // the caller may loosen the criterion knowingly
  EXPECT_NO_THROW(st.compute(*s));
}

// No loaded network at all: a clear error.
TEST(StaticStiffness, RefusesAGas) {
  auto s = simpleCubic(3, Vec3::Constant(-1e-6));  // gaps, no contact
  StaticStiffness st;
  EXPECT_THROW(st.compute(*s), InputError);
}

// A sphere held between two diametrically opposed contacts spins freely about that line: a local
// zero mode. Built in an orthorhombic simple cubic lattice (overlap 5e-3 r along x, 2e-3 r along
// y and z) by replacing one sphere with a smaller one that reaches its two x neighbours only.
// It must be found from the sphere's own block and pinned as a "local zero mode", a rotation
// about x; with the immediate pinning off, the factorisation meets the same mode as a zero (or
// round-off negative) pivot of the same turned DOF, and both routes give the same stiffness
// (tolerance 1e-10: the same system with the same DOF pinned, round-off apart).
TEST(StaticStiffness, SpinModeOfATwoContactSphereIsPinned) {
  const Vec3 delta(5e-7, 2e-7, 2e-7);
  auto s = simpleCubic(4, delta);
  const int site = 21;  // (1, 1, 1): i*16 + j*4 + k
  s->setSphereRadius(site, kR - 3.5e-7);  // overlaps its x neighbours by 1.5e-7, clears y and z
  StaticStiffness st;
  st.maxUnbalanced = 1;  // its neighbours are now out of balance; the zero mode is exact anyway
  const StaticStiffnessResult r = st.compute(*s);
  int local = 0;
  for (const PinnedDof& p : r.pinned)
    if (p.reason == "local zero mode") {
      ++local;
      EXPECT_EQ(p.body, site);
      EXPECT_LT(p.translation.norm(), 1e-12);
      EXPECT_NEAR(std::abs(p.rotation.normalized().x()), 1.0, 1e-12);
    }
  EXPECT_EQ(local, 1);
  EXPECT_LT(r.residual, 1e-10);
  EXPECT_LT(r.pinnedReaction, 1e-10);
  st.zeroModeTolerance = 0;  // immediate pinning off
  const StaticStiffnessResult z = st.compute(*s);
  int sameDof = 0;
  for (const PinnedDof& p : z.pinned) {
    EXPECT_NE(p.reason, "local zero mode");
    if (p.body == site) {
      ++sameDof;
      EXPECT_NEAR(std::abs(p.rotation.normalized().x()), 1.0, 1e-9);
    }
  }
  EXPECT_EQ(sameDof, 1);
  EXPECT_EQ(z.pinned.size(), r.pinned.size());
  EXPECT_LT(relativeError(z.C, r.C), 1e-10);
  StaticStiffness blocked;
  blocked.rotations = false;
  blocked.maxUnbalanced = 1;
  for (const PinnedDof& p : blocked.compute(*s).pinned) EXPECT_EQ(p.reason, "global translation");
}

// The rotation factor inverts Eq. (37): moduli made with zeta = 0.6 (and "blocked" ones with
// zeta = 1) give back 0.6 for every axis and for h and v, both definitions. Tolerance 1e-10:
// bisection to 1e-15 of a smooth monotonic function.
TEST(RotationFactor, InvertsEquation37) {
  // FCC: its normal moduli depend on k_s (a simple cubic lattice's do not, zeta would be moot).
  auto s = fcc(2, 4e-7);
  StaticStiffness st;
  const StaticStiffnessResult r = st.compute(*s);
  const Vec3 E06 = kinematicModuli(r.affineNormal, r.affineShear, 0.6);
  const Vec3 E1 = kinematicModuli(r.affineNormal, r.affineShear, 1.0);
  const RotationFactor z = rotationFactor(r.affineNormal, r.affineShear, E06, E1);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(z.zeta[i], 0.6, 1e-10);
    EXPECT_NEAR(z.zetaRotation[i], 0.6, 1e-10);
  }
  EXPECT_NEAR(z.zetaH, 0.6, 1e-10);
  EXPECT_NEAR(z.zetaV, 0.6, 1e-10);
  EXPECT_NEAR(z.zetaRotationH, 0.6, 1e-10);
  // E_i(zeta) grows with zeta: the kinematic estimate at zeta = 1 is the stiffest.
  EXPECT_TRUE((E06.array() < E1.array()).all());
}

// ---- sparse against dense ---------------------------------------------------------------------

// The CHOLMOD-preconditioned solve (refinement, and the GMRES fallback on its own) against a dense
// LU of the same pinned system, on a jittered lattice (out of balance is allowed here) with random
// shear forces, so K is not symmetric. Tolerance 1e-9: both converge to round-off of a system
// with condition ~1e4.
TEST(StaticStiffness, SparseSolveMatchesDenseSolve) {
  auto s = simpleCubic(3, Vec3(4e-6, 3e-6, 5e-6));
  std::mt19937_64 gen(6);
  std::normal_distribution<Real> Nd(0, 1);
  for (Vec3& p : s->bodies.pos) p += 1e-7 * Vec3(Nd(gen), Nd(gen), Nd(gen));
  s->refreshMembers();
  Scene held = heldState(*s);
  randomShearForces(held, 8);
  StaticStiffness st;
  st.maxUnbalanced = 10;
  // Feed the held state with its random shear forces: heldState() of it keeps them (dt = 0).
  const StaticStiffnessResult r = st.compute(held);
  EXPECT_GT(r.iterations, 0);  // K is not symmetric: the refinement had work to do
  EXPECT_LT(r.residual, 1e-10);

  const NetworkMatrix net = assembleNetwork(heldState(held), findRattlers(held), true);
  std::vector<int> keep;
  std::vector<char> pinned(net.size(), 0);
  for (const PinnedDof& p : r.pinned) pinned[p.dof] = 1;
  for (int d = 0; d < net.size(); ++d)
    if (!pinned[d]) keep.push_back(d);
  const Eigen::MatrixXd Kd = Eigen::MatrixXd(net.K);
  Eigen::MatrixXd Kr(keep.size(), keep.size()), fr(keep.size(), 6);
  for (size_t i = 0; i < keep.size(); ++i) {
    fr.row(i) = net.JE.row(keep[i]);
    for (size_t j = 0; j < keep.size(); ++j) Kr(i, j) = Kd(keep[i], keep[j]);
  }
  const Eigen::MatrixXd ur = Eigen::PartialPivLU<Eigen::MatrixXd>(Kr).solve(fr);
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(net.size(), 6);
  for (size_t i = 0; i < keep.size(); ++i) u.row(keep[i]) = ur.row(i);
  Mat6 volumeTerm = Mat6::Zero();
  const Vec6 sigma = voigt::fromTensor(loveWeberStress(heldState(held)));
  for (int J = 0; J < 3; ++J) volumeTerm.col(J) = sigma;
  const Mat6 C = -(net.SE + net.S * u) / held.cell.volume() + volumeTerm;
  EXPECT_LT(relativeError(r.C, C), 1e-9) << r.C << "\n\n" << C;
  // The GMRES fallback alone reaches the same answer.
  st.forceGmres = true;
  const StaticStiffnessResult g = st.compute(held);
  EXPECT_EQ(g.iterations, 0);
  EXPECT_GT(g.gmresIterations, 0);
  EXPECT_LT(g.residual, 1e-10);
  EXPECT_LT(relativeError(g.C, C), 1e-9);
}
