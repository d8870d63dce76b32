#pragma once
// Love-Weber average stress and YADE's unbalanced force.
#include "core/Scene.hpp"
#include "core/Voigt.hpp"

namespace trueaniso {

// sigma = (1/V) sum_c F_c (x) L_c over contacts, F_c the force on body 2, L_c the branch from
// body 1 to body 2 (clumps: between clump centres). Compression is positive, so this is minus
// YADE's utils.getStress(). Not symmetrised: the antisymmetric part measures imbalance.
Mat3 loveWeberStress(const Scene& scene);

// YADE's Shop::unbalancedForce(useMaxForce=False): mean |resultant force| over bodies divided by
// the mean |contact force| over contacts.
Real unbalancedForce(const Scene& scene);

// The same for moments about the body centres: mean |resultant torque| over bodies divided by
// (mean |contact force| x mean lever arm, half the mean member-centre distance of the contacts).
// Clumps held with rotations blocked keep torques that a probe with rotations free would relax.
Real unbalancedTorque(const Scene& scene);


// d sigma_I / d e_I of an affine strain of Voigt component I (xx, yy, zz, then engineering shears
// yz, xz, xy): the diagonal of Eq. (32)'s stiffness (contact springs only), an upper bound of the
// true stiffness that the cell controllers use to scale their gain.
Vec6 affineStiffness(const Scene& scene);

// The stress, the affine stiffness and the unbalanced force that a cell controller reads every
// step, from one pass over the contacts instead of three. The four functions above and this one
// add the same terms in the same blocks, lanes and order (measure/CellSums.hpp), so they agree to
// the bit, and with the sums the force loop makes while it computes the forces (cellMeasures).
struct ContactMeasures {
  Mat3 stress;      // loveWeberStress
  Vec6 stiffness;   // affineStiffness
  Real unbalanced;  // unbalancedForce
};
ContactMeasures contactMeasures(const Scene& scene);

// The same measures, from the sums the force loop made in this step (Scene::measured,
// measure/CellSums.hpp) when it made them, else from contactMeasures: what the cell controllers
// read. The same bits either way.
ContactMeasures cellMeasures(const Scene& scene);

// Principal values of the symmetric part of a stress tensor, largest first.
Vec3 principalStresses(const Mat3& sigma);

}  // namespace trueaniso
