#pragma once
// Rattlers of a held state: bodies that cannot carry load. A body with no contact is free; a body
// with one contact cannot balance a force N > 0 and, in the static tangent, follows its neighbour
// without changing any force (with rotations free it can even roll: a zero mode). Removing such a
// body can leave a neighbour with fewer than two contacts, so the removal is repeated until every
// remaining body has at least two contacts with remaining bodies (the "mechanical" network whose
// coordination Eq. 14 approximates by removing the 0- and 1-contact bodies once).
#include <vector>

#include "core/Scene.hpp"

namespace trueaniso {

// rattler[b] != 0 for every removed body. Needs the incidence lists of a detected contact list.
std::vector<char> findRattlers(const Scene& held);

}  // namespace trueaniso
