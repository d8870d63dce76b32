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
  explicit HertzMindlin(const Material& m)
      : ratio_(m.stiffnessRatio()), mu_(m.friction), Cn_(m.Cn()), Cs_(m.Cs()),
        hertzUnit_(4.0 / 3.0 * m.contactModulus() * std::sqrt(0.5)), beta_(m.rollingStiffness),
        etaR_(m.rollingFriction) {}

  // What one evaluation gives a touching contact.
  struct Response {
    Real N;         // normal force (> 0)
    Vec3 Fs;        // tangential force on sphere 2
    bool sliding;   // at the Coulomb cap after this increment
  };

  // One touching contact, one step. delta > 0: overlap; rbar: Eq. (7); n: the current unit
  // normal (sphere 1 -> 2). History: `loaded` (the contact carried a force at the last
  // evaluation), its normal `nPrev` and tangential force `FsPrev`. Kinematics of the step: the
  // tangential relative displacement `dus` (in the plane normal to n) and the `twist`, the
  // pair's spin about n times dt.
  // Inlined into the force loop: a call per contact costs ~6 % of the loop (callgrind).
  __attribute__((always_inline)) inline Response evaluate(Real delta, Real rbar, const Vec3& n, bool loaded,
                                                          const Vec3& nPrev, const Vec3& FsPrev, const Vec3& dus,
                                                          Real twist) const {
    // N = (4/3) E* sqrt(R*) delta^(3/2), R* = rbar/2; k_s = (C_s/C_n) 1.5 N/delta written with
    // sqrt(delta) instead of a division (the same number, one operation fewer per contact).
    const Real sqrtDelta = std::sqrt(delta);
    const Real coef = hertzUnit_ * std::sqrt(rbar);
    Response r;
    r.N = coef * delta * sqrtDelta;
    const Real ks = ratio_ * 1.5 * coef * sqrtDelta;
    r.Fs = loaded ? rotateWithContact(FsPrev, nPrev, n, twist) : Vec3::Zero();  // new contact: no history
    r.Fs -= ks * dus;
    r.sliding = capShear(r.Fs, r.N);
    return r;
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
    if (twist == 0.0 && a == b) return Fs;
    const Real c = a.dot(b);
    if (c <= -1.0 + 1e-12) return Vec3::Zero();  // normal reversed: the old frame is meaningless
    const Vec3 w = a.cross(b);
    Vec3 v = c * Fs + w.cross(Fs) + (w.dot(Fs) / (1.0 + c)) * w;
    if (twist != 0.0) {
      // Cayley form of a rotation about b: exactly orthogonal, no trigonometric call; its
      // angle 2 atan(twist/2) equals twist to O(twist^3), far below the step's other errors.
      const Real t = 0.5 * twist, s = 1.0 / (1.0 + t * t);
      v = ((1.0 - t * t) * s) * v + (2.0 * t * s) * b.cross(v);
    }
    return v - b.dot(v) * b;  // keep it in the tangent plane against round-off drift
  }

  // A vector the cap has already scaled lies within a few ulps of it and is left as it is (slack
  // 8 ulps of its squared norm): re-evaluating a contact without increment must not rescale it
  // by 1 - 1e-16 each time.
  static constexpr Real kCapSlack = 1.0 + 8.0 * std::numeric_limits<Real>::epsilon();
  // Coulomb: |Fs| <= mu N. Returns true if the force was capped (sliding). Written out rather
  // than calling capMagnitude: that call changed GCC 12's register allocation of the sheared
  // force loop, and the paper's loop keeps its machine code (docs/rolling.md).
  bool capShear(Vec3& Fs, Real N) const {
    const Real cap = mu_ * N;
    const Real f2 = Fs.squaredNorm();
    if (f2 > cap * cap * kCapSlack) {
      Fs *= cap / std::sqrt(f2);
      return true;
    }
    return false;
  }
  // The same cap with the same slack for the rolling moment.
  static bool capMagnitude(Vec3& v, Real cap) {
    const Real v2 = v.squaredNorm();
    if (v2 > cap * cap * kCapSlack) {
      v *= cap / std::sqrt(v2);
      return true;
    }
    return false;
  }

 private:
  Real ratio_, mu_, Cn_, Cs_;
  Real hertzUnit_;  // (4/3) E* sqrt(1/2): N = hertzUnit_ sqrt(rbar) delta^(3/2)
  Real beta_, etaR_;  // rolling sub-model: k_r = beta_ k_s rbar^2, cap etaR_ rbar N
};

}  // namespace trueaniso
