#pragma once
// The state a static stiffness is taken at: the scene as it is, every contact sticking. The
// contact list and forces are evaluated afresh on a copy (positions may have moved since the last
// force evaluation, e.g. by the integrator's final step), with dt = 0 so that no increment is
// added, and with infinite friction (sliding suppressed, as in the probe).
#include <vector>

#include "core/Scene.hpp"
#include "statics/ContactTangent.hpp"

namespace trueaniso {

Scene heldState(const Scene& scene);

// Force and torque balance of a held state. forces: YADE's unbalanced force (mean |resultant| over
// bodies / mean |contact force|), the criterion a probe waits on; torques: the same with moments,
// mean |resultant torque| / (mean |contact force| x mean lever arm).
struct Balance {
  Real forces = 0, torques = 0;
};
Balance balance(const Scene& held);

// Refuses (InputError) a state whose force, or with rotations free torque, imbalance exceeds
// `limit`: its tangent is not what a probe from that state converges to, because the probe would
// first relax the imbalance itself.
void requireBalance(const Scene& held, Real limit, bool rotations);

// Everything the linearisation needs about contact c of a held state.
HeldContact heldContact(const Scene& held, int c);

}  // namespace trueaniso
