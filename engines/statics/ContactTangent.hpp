#pragma once
// Linearisation of the dynamic contact law (HertzMindlin + ContactForces) about a held contact,
// with sliding suppressed. It must be the derivative of exactly what the force loop computes, so
// that the static answer is the limit the quasi-static probe converges to:
//  - normal force N(delta) along n from member centre 1 to member centre 2: dN = -k_n n.dd;
//  - the normal direction turns with the member centres: dn = P dd / l (P = I - n n);
//  - the shear force is carried with the contact frame (minimal rotation n -> n + dn, then the
//    spin of the pair about n by tau = n.(th_a + th_b)/2) and loaded by k_s times the tangential
//    part of the contact point's relative displacement du;
//  - the contact point sits mid-overlap (lever arms r - delta/2 along n), and the arms change with
//    the overlap, the normal and the bodies' rotations, which is why torques get initial-force
//    terms;
//  - the affine field of the cell acts on the branch L between body centres (dd, du, dL += E L).
// The body increments q = [u_a, th_a, u_b, th_b] and the Voigt strain e (extension positive,
// engineering shears) give dR = J q + JE e for R = [F_a, T_a, F_b, T_b], the forces and torques
// the contact applies to its two bodies, and d(sigma V) = S q + (SEnormal + SEshear + SEgeometric) e
// for the Love-Weber sum F (x) L. SEnormal + SEshear is what Eq. (32) keeps (k_n, k_s acting on
// the affine relative displacement); everything proportional to the existing forces is in
// SEgeometric, so that the comparison with Eq. (32) is exact.
#include <Eigen/Core>

#include "core/Types.hpp"
#include "statics/Voigt.hpp"

namespace trueaniso {

struct HeldContact {
  Vec3 normal;      // n, unit, from member 1 to member 2
  Vec3 shearForce;  // Fs on body 2, tangent to n
  Vec3 branch;      // L, body centre 1 to body centre 2 (image aware)
  Vec3 offset1, offset2;  // member centre minus body centre, world frame (zero for spheres)
  Real normalForce = 0;   // N
  Real kn = 0, ks = 0;    // Eqs. (5)-(6)
  Real distance = 0;      // l = |member centre 2 - member centre 1| = r1 + r2 - delta
  Real arm1 = 0, arm2 = 0;  // r1 - delta/2, r2 - delta/2
};

struct ContactTangent {
  Eigen::Matrix<Real, 12, 12> J;
  Eigen::Matrix<Real, 12, 6> JE;
  Eigen::Matrix<Real, 6, 12> S;
  // Affine d(sigma V)/de split as Eq. (32): SEnormal from k_n n n, SEshear from k_s (I - n n),
  // SEgeometric from the existing forces.
  Mat6 SEnormal, SEshear, SEgeometric;
};

namespace detail {
inline Mat3 crossMatrix(const Vec3& v) {  // crossMatrix(v) w = v x w
  Mat3 m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}
// Voigt rows of sym(A (x) L) for a 3 x m matrix A of vector increments: row I = (i, j) is
// (L_j A_i + L_i A_j) / 2.
template <int M>
Eigen::Matrix<Real, 6, M> symmetricOuter(const Eigen::Matrix<Real, 3, M>& A, const Vec3& L) {
  Eigen::Matrix<Real, 6, M> out;
  for (int I = 0; I < 6; ++I) {
    const int i = voigt::kRow[I], j = voigt::kCol[I];
    out.row(I) = 0.5 * (L[j] * A.row(i) + L[i] * A.row(j));
  }
  return out;
}
}  // namespace detail

inline ContactTangent linearise(const HeldContact& h) {
  using detail::crossMatrix;
  using M3x12 = Eigen::Matrix<Real, 3, 12>;
  using M3x6 = Eigen::Matrix<Real, 3, 6>;
  const Mat3 I3 = Mat3::Identity();
  const Vec3& n = h.normal;
  const Vec3& Fs = h.shearForce;
  const Vec3& L = h.branch;
  const Real l = h.distance;
  const Mat3 nn = n * n.transpose();
  const Mat3 P = I3 - nn;
  const Vec3 arm1 = h.offset1 + h.arm1 * n;
  const Vec3 arm2 = h.offset2 - h.arm2 * n;
  const Vec3 F = h.normalForce * n + Fs;

  // dd (member centres) and du (contact point, what loads the shear spring) per unit q.
  M3x12 D, A;
  D << -I3, crossMatrix(h.offset1), I3, -crossMatrix(h.offset2);
  A << -I3, crossMatrix(arm1), I3, -crossMatrix(arm2);
  Eigen::Matrix<Real, 1, 12> twist = Eigen::Matrix<Real, 1, 12>::Zero();
  twist.segment<3>(3) = 0.5 * n.transpose();
  twist.segment<3>(9) = 0.5 * n.transpose();

  const Mat3 Kc = h.kn * nn + h.ks * P;
  // N dn and the frame rotation of Fs (which keeps it tangent: -n (Fs . dn)).
  const Mat3 G = (h.normalForce / l) * P - n * Fs.transpose() / l;
  const M3x12 Phi = -Kc * A + G * D + n.cross(Fs) * twist;  // dF per unit q
  const Mat3 Psi = -Kc + G;                                  // dF per unit E L
  // Lever arms: arm1 = rho1 + (r1 - delta/2) n, arm2 = rho2 - (r2 - delta/2) n, d delta = -n.dd.
  const Mat3 H1 = 0.5 * nn + (h.arm1 / l) * P;
  const Mat3 H2 = 0.5 * nn + (h.arm2 / l) * P;
  M3x12 Theta1 = H1 * D, Theta2 = -H2 * D;  // d arm per unit q
  Theta1.block<3, 3>(0, 3) -= crossMatrix(h.offset1);
  Theta2.block<3, 3>(0, 9) -= crossMatrix(h.offset2);

  const Mat3 Fx = crossMatrix(F), A1x = crossMatrix(arm1), A2x = crossMatrix(arm2);
  ContactTangent t;
  t.J.block<3, 12>(0, 0) = -Phi;                      // F_a = -F
  t.J.block<3, 12>(3, 0) = Fx * Theta1 - A1x * Phi;   // T_a = -arm1 x F
  t.J.block<3, 12>(6, 0) = Phi;                       // F_b = F
  t.J.block<3, 12>(9, 0) = -Fx * Theta2 + A2x * Phi;  // T_b = arm2 x F

  const M3x6 W = voigt::branchMap(L);
  const M3x6 dFe = Psi * W;
  t.JE.block<3, 6>(0, 0) = -dFe;
  t.JE.block<3, 6>(3, 0) = Fx * H1 * W - A1x * dFe;
  t.JE.block<3, 6>(6, 0) = dFe;
  t.JE.block<3, 6>(9, 0) = Fx * H2 * W + A2x * dFe;

  // d(F (x) L) with dL = u_b - u_a + E L (body centres: rotations do not move L).
  M3x12 Dl = M3x12::Zero();
  Dl.block<3, 3>(0, 0) = -I3;
  Dl.block<3, 3>(0, 6) = I3;
  t.S = detail::symmetricOuter<12>(Phi, L);
  // F (x) dL: its Voigt rows are (F_i dL_j + F_j dL_i)/2, i.e. symmetricOuter of dL against F.
  t.S += detail::symmetricOuter<12>(Dl, F);
  t.SEnormal = detail::symmetricOuter<6>(M3x6(-h.kn * nn * W), L);
  t.SEshear = detail::symmetricOuter<6>(M3x6(-h.ks * P * W), L);
  t.SEgeometric = detail::symmetricOuter<6>(M3x6(G * W), L) + detail::symmetricOuter<6>(W, F);
  return t;
}

}  // namespace trueaniso
