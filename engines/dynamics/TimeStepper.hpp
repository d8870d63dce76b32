#pragma once
// Time step from the current contact stiffnesses, as YADE's GlobalStiffnessTimeStepper: a safety
// fraction of the smallest sqrt(inertia / stiffness) over the bodies, each body taken alone with
// its neighbours held. Two rules for that body bound (docs/time-step.md measures both):
//  - stiffnessBound: sqrt(m / sum k_n) and sqrt(I_min / sum k_s l^2), l = |member offset| + radius;
//  - perAxisBound: each block's stiffest mode, derived below.
//
// The stiffness of one body. A contact at arm l (body centre -> contact point, world frame) with
// unit normal n, normal stiffness k_n and tangential stiffness k_s resists a small displacement u
// of the contact point with the force -K_c u, K_c = k_n n n^T + k_s (1 - n n^T). A translation u of
// the body moves the contact point by u; a small rotation theta moves it by theta x l. Hence
//  - translation: K_t = sum K_c, whose largest eigenvalue is at most sum k_n (k_s <= k_n);
//  - rotation: K_r = sum [l]^T K_c [l] ([l] theta = l x theta), so about a unit axis a
//        a^T K_r a = k_s |l x a|^2 + (k_n - k_s) (n . (l x a))^2,
//    plus the rolling spring's k_r (1 - (n . a)^2) when it is on. For a sphere l = -/+ r n, so the
//    second term vanishes and a contact stiffens the axes normal to it only: k_s r^2 (1 - (n.a)^2),
//    on average 2/3 of k_s r^2. For a clump the normal force has a lever arm too (the second term),
//    and an arm along an axis (a dimer's contact at its tip) gives that axis no stiffness at all.
// Each block gives the body's stiffest mode of that kind: omega_t^2 = lambda_max(K_t) / m and
// omega_r^2 = lambda_max(D^-1/2 K_r D^-1/2), K_r in the body's principal frame, D = diag(I_1, I_2,
// I_3); its diagonal entries are the per-axis ratios k_aa / I_a, and for a sphere (isotropic I,
// every axis principal) it is the stiffest axis. The bound is 1 / max(omega_t, omega_r).
// What the bound leaves out: the cross terms between translation and rotation of the body (the
// force of a contact's tangential spring also turns the body) and the coupling to the neighbours,
// which move too (a pair of equal bodies alone vibrates at sqrt(2) omega, hence YADE's sqrt 2).
// Both raise the true highest frequency of the packing above the body's own; the safety factor is
// measured against them (docs/time-step.md: energy drift of an undamped packing against dt).
#include "core/Engine.hpp"

namespace trueaniso {

class TimeStepper : public Engine {
 public:
  TimeStepper() { every = 10; }
  // dt = safety x the bound of the rule below.
  Real safety = 0.5;
  // The rule: perAxisBound when true, else stiffnessBound.
  bool perAxis = false;
  // Upper bound used while there are few or no contacts (a loose gas would otherwise get a huge
  // step right before its first collisions); the caller sets it from the expected contact force.
  Real maxDt = 1.0;
  // The reference rule, stiffnessBound at referenceSafety capped by referenceMaxDt (<= 0: maxDt x
  // referenceSafety / safety, the cap at the reference factor), sets scene.referenceDt: the unit of
  // time of the servos' per-step settings. Under the default rule it is dt itself, to the bit.
  Real referenceSafety = 0.5;
  Real referenceMaxDt = 0;

  void apply(Scene& scene) override;
  std::string name() const override { return "TimeStepper"; }

  // min over bodies of sqrt(m / sum k_n) and sqrt(I_min / sum k_s l^2), without the safety factor.
  static Real stiffnessBound(const Scene& scene);
  // 1 / max over bodies of max(omega_t, omega_r) (header comment), without the safety factor.
  static Real perAxisBound(const Scene& scene);
  // Both bounds from one walk over the bodies' contacts (apply's call): the same values as the two
  // functions above. perAxis = false leaves .perAxis infinite.
  struct Bounds {
    Real stiffness, perAxis;
  };
  static Bounds bounds(const Scene& scene, bool perAxis);
  // omega^2 = max(omega_t^2, omega_r^2) of body b (header comment); 0 without loaded contacts.
  static Real stiffestMode(const Scene& scene, int b);
  // An upper bound of stiffestMode(scene, b) from sums of scalars: lambda_max of a sum of positive
  // semi-definite matrices is at most the sum of theirs. A contact's K_c has k_n (k_s <= k_n, else
  // k_s), so K_t's is at most sum k_n; [l]^T K_c [l] has at most k l^2 with l <= |offset| + radius,
  // and a sphere's k_s l^2 (1 - n n^T) has k_s l^2; the rolling spring adds at most k_r; and
  // D^-1/2 K_r D^-1/2 has at most lambda_max(K_r) / I_min.
  static Real stiffestModeBound(const Scene& scene, int b);
  // Largest step for which every single contact, alone between its two bodies, is stable: 2/omega
  // of the pair, omega^2 the largest eigenvalue of K_c^1/2 W K_c^1/2 with W the pair's mobility at
  // the contact point, W = sum over both bodies of (1/m + [l]^T I^-1 [l]) (I^-1 in the world
  // frame), plus the rolling spring's k_r (1/I_1 + 1/I_2) (an upper bound for their sum). Any other
  // contact only raises the highest frequency, so a step above this limit cannot be stable and is
  // refused (NewtonIntegrator::checkStability).
  static Real criticalPairStep(const Scene& scene);
};

}  // namespace trueaniso
