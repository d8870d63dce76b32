#pragma once
// Every contact quantity (list, normals, branch vectors, overlaps, forces) recomputed for the
// scene's current positions with no tangential increment (dt = 0): what a loaded, edited or
// just-integrated scene needs before it is measured. The one place this is done: the static
// solve's held state, specimen loading and the probes' restore all call it.
//
// Tangential forces are carried with the contact frame; where the frame has not changed (the
// same positions) they come back bit for bit, however often the refresh runs.
#include "core/Scene.hpp"

namespace trueaniso {

void refreshContacts(Scene& scene);

}  // namespace trueaniso
