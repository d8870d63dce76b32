#pragma once
// The simplified Hertz-Mindlin law of the paper (Eqs. 5-7): the whole per-contact evaluator, as a
// HOOMD pair evaluator or a LAMMPS granular model owns its contact. The generic contact loop
// (dynamics/ContactForces) supplies the geometry and kinematics of a pair and stores what comes
// back; the static solve (statics/) and the measures take their stiffnesses from here too.
//  - normal sub-model: Hertz force in closed form from the overlap, whose tangent is Eq. (5);
//  - tangential sub-model: incremental, k_s of Eq. (6), carried with the contact frame, capped
//    at mu N (Coulomb);
//  - rolling sub-model (optional, not in the paper; off unless Material::rolling()): the
//    elastic-plastic rolling spring of Iwashita & Oda (1998) as Ai et al. (2011) classify it
//    ("type C", here without its dashpot): k_r = beta k_s rbar^2, the rolling moment
//    incremented by -k_r times the relative rolling rotation and capped at eta_r rbar N.
//    Carried with the contact frame like the shear force. No twisting resistance.
#include <cmath>
#include <limits>

#include "core/Material.hpp"
#include "core/Types.hpp"

namespace trueaniso {

class HertzMindlin {
 public:
  // The law's constants, computed once from the material. A host that keeps them with each
  // contact (the YADE plugin's SimplifiedMindlinPhys) builds the law from them per contact,
  // with the contact's own friction, at the cost of a copy.
  struct Constants {
    Real ratio, mu, Cn, Cs;
    Real hertzUnit;   // (4/3) E* sqrt(1/2): N = hertzUnit sqrt(rbar) delta^(3/2)
    Real beta, etaR;  // rolling sub-model
  };
  static Constants constants(const Material& m) {
    return {m.stiffnessRatio(), m.friction, m.Cn(), m.Cs(), 4.0 / 3.0 * m.contactModulus() * std::sqrt(0.5),
            m.rollingStiffness, m.rollingFriction};
  }
  explicit HertzMindlin(const Constants& c)
      : ratio_(c.ratio), mu_(c.mu), Cn_(c.Cn), Cs_(c.Cs), hertzUnit_(c.hertzUnit), beta_(c.beta), etaR_(c.etaR) {}
  explicit HertzMindlin(const Material& m) : HertzMindlin(constants(m)) {}

  // Touching contacts of one step, held by component so that the law runs over several contacts
  // at once: the compiler puts two contacts in the two lanes of an SSE2 register (the x86-64
  // baseline, no FMA), where each lane does the arithmetic of the scalar law in its order, so a
  // contact's result does not depend on its neighbours in the batch. The force loop fills a batch
  // with the contacts' geometry, kinematics and history, evaluates it, and reads the forces back.
  struct Batch {
    static constexpr int kSize = 32;
    Real nx[kSize], ny[kSize], nz[kSize];  // the current unit normal n (sphere 1 -> 2)
    Real px[kSize], py[kSize], pz[kSize];  // the normal at the last evaluation
    Real fx[kSize], fy[kSize], fz[kSize];  // in: the tangential force at the last evaluation; out: this step's
    Real ux[kSize], uy[kSize], uz[kSize];  // dus: the step's tangential relative displacement (normal to n)
    Real twist[kSize];                     // the pair's spin about n times dt
    Real delta[kSize], rbar[kSize];        // overlap > 0; Eq. (7)
    Real loaded[kSize];                    // 1: the contact carried a force at the last evaluation, else 0
    Real N[kSize];                         // out: normal force (> 0)
    Real sliding[kSize];                   // out: 1 if at the Coulomb cap after this increment, else 0
  };

  // Contacts 0..m-1 of the batch, one step each. N = (4/3) E* sqrt(R*) delta^(3/2), R* = rbar/2;
  // k_s = (C_s/C_n) 1.5 N/delta written with sqrt(delta) instead of a division. The tangential
  // force is the last one carried with the contact frame (rotateWithContact; a new contact has
  // none), incremented by -k_s dus and capped at mu N (Coulomb). Branch-free, so that the loop
  // vectorises: both sides of each choice are computed and one is kept.
  // Out of line (contact/HertzMindlin.cpp), built with the vectorising flags of engines/CMakeLists.txt.
  void evaluate(Batch& q, int m) const;

  // One contact alone, through a batch of one (for tests and one-off callers): the same
  // arithmetic as in a full batch, since the lanes are independent.
  struct Response {
    Real N;        // normal force (> 0)
    Vec3 Fs;       // tangential force on sphere 2
    bool sliding;  // at the Coulomb cap after this increment
  };
  Response evaluate(Real delta, Real rbar, const Vec3& n, bool loaded, const Vec3& nPrev, const Vec3& FsPrev,
                    const Vec3& dus, Real twist) const {
    Batch q;
    q.nx[0] = n.x(); q.ny[0] = n.y(); q.nz[0] = n.z();
    q.px[0] = nPrev.x(); q.py[0] = nPrev.y(); q.pz[0] = nPrev.z();
    q.fx[0] = FsPrev.x(); q.fy[0] = FsPrev.y(); q.fz[0] = FsPrev.z();
    q.ux[0] = dus.x(); q.uy[0] = dus.y(); q.uz[0] = dus.z();
    q.twist[0] = twist; q.delta[0] = delta; q.rbar[0] = rbar; q.loaded[0] = loaded ? 1.0 : 0.0;
    evaluate(q, 1);
    return {q.N[0], Vec3(q.fx[0], q.fy[0], q.fz[0]), q.sliding[0] != 0};
  }

  // Normal sub-model.
  // Hertz: N = (4/3) E* sqrt(R*) delta^(3/2), R* = r1 r2/(r1+r2) = rbar/2 (Eq. 7).
  Real normalForce(Real delta, Real rbar) const {
    return delta > 0 ? hertzUnit_ * std::sqrt(rbar) * delta * std::sqrt(delta) : 0.0;
  }
  // dN/d delta = (3/2) N/delta = 2 E* sqrt(R* delta), algebraically C_n rbar^(1/3) N^(1/3) (Eq. 5).
  // The one place the tangent of the force law is written; 0 for a contact that carries nothing.
  static Real normalStiffness(Real N, Real delta) { return N > 0 && delta > 0 ? 1.5 * N / delta : 0.0; }

  // Tangential sub-model.
  // k_s/k_n = C_s/C_n = 2(1-nu)/(2-nu) for every contact (Eqs. 5-6).
  Real shearStiffness(Real kn) const { return ratio_ * kn; }
  Real shearToNormal() const { return ratio_; }
  Real friction() const { return mu_; }

  // Eqs. (5) and (6) written as in the paper, for the fabric tensors and for tests.
  Real knFromForce(Real N, Real rbar) const { return Cn_ * std::cbrt(rbar * N); }
  Real ksFromForce(Real N, Real rbar) const { return Cs_ * std::cbrt(rbar * N); }

  // Rolling sub-model (docs/rolling.md).
  // k_r = beta k_s rbar^2: Iwashita & Oda's rolling stiffness, which follows the Hertz-Mindlin
  // k_s (so it grows with the contact force as the contact area does); rbar of Eq. (7) is the
  // radius of two equal spheres.
  Real rollingStiffness(Real ks, Real rbar) const { return beta_ * ks * rbar * rbar; }
  // Largest rolling moment eta_r rbar N: the normal force's lever of eta_r rbar across the contact.
  Real rollingCap(Real N, Real rbar) const { return etaR_ * rbar * N; }

  // One touching contact, one step, of the rolling moment on sphere 2 (sphere 1 receives its
  // opposite). History as in `evaluate`; `dRoll`: the relative rolling rotation of the step,
  // (omega_2 - omega_1) dt in the plane normal to n; `ks`: this step's tangential stiffness.
  // `capped` says whether the cap acted.
  __attribute__((always_inline)) inline Vec3 rollingMoment(Real rbar, Real N, Real ks, const Vec3& n, bool loaded,
                                                           const Vec3& nPrev, const Vec3& MPrev, const Vec3& dRoll,
                                                           Real twist, bool& capped) const {
    Vec3 M = loaded ? rotateWithContact(MPrev, nPrev, n, twist) : Vec3::Zero();
    M -= rollingStiffness(ks, rbar) * dRoll;
    capped = capMagnitude(M, rollingCap(N, rbar));
    return M;
  }

  // Carry the shear force with the contact frame: the minimal rotation taking the previous
  // normal a onto the current one b, then the spin of the pair about b. Both are exact
  // rotations, so a rigid rotation of a loaded pair never changes the force magnitude
  // (YADE's small-angle update does, by O(angle^2) per step). An unchanged frame (b == a
  // bitwise, no twist) carries the force unchanged, bit for bit: a contact refresh at the same
  // positions (dt = 0) must not drift by round-off however often it runs.
  __attribute__((always_inline)) static inline Vec3 rotateWithContact(const Vec3& Fs, const Vec3& a, const Vec3& b,
                                                                     Real twist) {
    Real x = Fs.x(), y = Fs.y(), z = Fs.z();
    carry(x, y, z, a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), twist);
    return Vec3(x, y, z);
  }

  // rotateWithContact on components, (fx, fy, fz) carried from normal a to normal b, in place.
  // Branch-free (see evaluate); the order of every sum is that of Eigen's products on Vec3 (a dot
  // product is (x x' + y y') + z z'), so both callers keep the bits of the vector form.
  __attribute__((always_inline)) static inline void carry(Real& fx, Real& fy, Real& fz, Real ax, Real ay, Real az,
                                                         Real bx, Real by, Real bz, Real twist) {
    const bool unchanged = (twist == 0.0) & (ax == bx) & (ay == by) & (az == bz);  // &: no branch
    const Real c = ax * bx + ay * by + az * bz;
    const bool reversed = c <= -1.0 + 1e-12;  // normal reversed: the old frame is meaningless
    const Real wx = ay * bz - az * by, wy = az * bx - ax * bz, wz = ax * by - ay * bx;
    const Real along = (wx * fx + wy * fy + wz * fz) / (1.0 + c);
    Real vx = c * fx + (wy * fz - wz * fy) + along * wx;
    Real vy = c * fy + (wz * fx - wx * fz) + along * wy;
    Real vz = c * fz + (wx * fy - wy * fx) + along * wz;
    // Cayley form of a rotation about b: exactly orthogonal, no trigonometric call; its angle
    // 2 atan(twist/2) equals twist to O(twist^3), far below the step's other errors.
    const Real t = 0.5 * twist, s = 1.0 / (1.0 + t * t);
    const Real k1 = (1.0 - t * t) * s, k2 = 2.0 * t * s;
    const Real tx = k1 * vx + k2 * (by * vz - bz * vy);
    const Real ty = k1 * vy + k2 * (bz * vx - bx * vz);
    const Real tz = k1 * vz + k2 * (bx * vy - by * vx);
    if (twist != 0.0) { vx = tx; vy = ty; vz = tz; }
    const Real p = bx * vx + by * vy + bz * vz;  // keep it in the tangent plane against round-off drift
    vx -= p * bx; vy -= p * by; vz -= p * bz;
    fx = unchanged ? fx : reversed ? 0.0 : vx;
    fy = unchanged ? fy : reversed ? 0.0 : vy;
    fz = unchanged ? fz : reversed ? 0.0 : vz;
  }

  // A vector the cap has already scaled lies within a few ulps of it and is left as it is (slack
  // 8 ulps of its squared norm): re-evaluating a contact without increment must not rescale it
  // by 1 - 1e-16 each time.
  static constexpr Real kCapSlack = 1.0 + 8.0 * std::numeric_limits<Real>::epsilon();
  // The one rule of a cap (Coulomb's |Fs| <= mu N in evaluate, the rolling moment's): a vector of
  // squared magnitude v2 beyond the cap, with the slack, is scaled by capScale onto it.
  static bool beyondCap(Real v2, Real cap) { return v2 > cap * cap * kCapSlack; }
  static Real capScale(Real v2, Real cap) { return cap / std::sqrt(v2); }
  static bool capMagnitude(Vec3& v, Real cap) {
    const Real v2 = v.squaredNorm();
    if (!beyondCap(v2, cap)) return false;
    v *= capScale(v2, cap);
    return true;
  }

 private:
  Real ratio_, mu_, Cn_, Cs_;
  Real hertzUnit_;  // (4/3) E* sqrt(1/2): N = hertzUnit_ sqrt(rbar) delta^(3/2)
  Real beta_, etaR_;  // rolling sub-model: k_r = beta_ k_s rbar^2, cap etaR_ rbar N
};

}  // namespace trueaniso
