#pragma once
// The simplified Hertz-Mindlin law of the paper (Eqs. 5-7) as a small evaluator that the generic
// contact loop calls per contact, in the spirit of a HOOMD pair evaluator / LAMMPS sub-model:
//  - normal: Hertz force in closed form from the overlap, whose tangent is Eq. (5);
//  - tangential: incremental, k_s of Eq. (6), rotated with the contact frame, Coulomb cap mu N.
#include <cmath>

#include "core/Material.hpp"
#include "core/Types.hpp"

namespace trueaniso {

class HertzMindlin {
 public:
  explicit HertzMindlin(const Material& m)
      : Estar_(m.contactModulus()), ratio_(m.stiffnessRatio()), mu_(m.friction),
        Cn_(m.Cn()), Cs_(m.Cs()) {}

  // Hertz: N = (4/3) E* sqrt(R*) delta^(3/2) with R* = r1 r2/(r1+r2) = rbar/2 (Eq. 7).
  Real normalForce(Real delta, Real rbar) const {
    return delta > 0 ? hertzCoefficient(rbar) * delta * std::sqrt(delta) : 0.0;
  }
  Real hertzCoefficient(Real rbar) const { return 4.0 / 3.0 * Estar_ * std::sqrt(0.5 * rbar); }
  // dN/d delta = (3/2) N/delta = 2 E* sqrt(R* delta); algebraically C_n rbar^(1/3) N^(1/3).
  static Real tangentFromForce(Real N, Real delta) { return delta > 0 ? 1.5 * N / delta : 0.0; }
  // Eq. (5) and Eq. (6) written as in the paper, for tests and for the fabric tensors.
  Real knFromForce(Real N, Real rbar) const { return Cn_ * std::cbrt(rbar * N); }
  Real ksFromForce(Real N, Real rbar) const { return Cs_ * std::cbrt(rbar * N); }
  Real shearToNormal() const { return ratio_; }
  Real friction() const { return mu_; }

  // Carry the shear force with the contact frame: the minimal rotation taking the previous
  // normal a onto the current one b, then the spin of the pair about b. Both are exact
  // rotations, so a rigid rotation of a loaded pair never changes the force magnitude
  // (YADE's small-angle update does, by O(angle^2) per step).
  __attribute__((always_inline)) static inline Vec3 rotateWithContact(const Vec3& Fs, const Vec3& a, const Vec3& b, Real twist) {
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

  // Incremental tangential force: Fs <- Fs - k_s dus, then |Fs| <= mu N. Returns true if sliding.
  bool updateShear(Vec3& Fs, const Vec3& dus, Real ks, Real N) const {
    Fs -= ks * dus;
    const Real cap = mu_ * N;
    const Real f2 = Fs.squaredNorm();
    if (f2 > cap * cap) {
      Fs *= cap / std::sqrt(f2);
      return true;
    }
    return false;
  }

 private:
  Real Estar_, ratio_, mu_, Cn_, Cs_;
};

}  // namespace trueaniso
