#pragma once
// Bodies numbered along a space-filling curve (Morton, or Z, order), as HOOMD sorts its particles:
// the contact loop walks pairs in the order of their first member and writes forces to both
// bodies; with bodies numbered in space, the second body of a pair is a near neighbour in memory
// too, so a step's reads and writes stay in cache instead of jumping across the whole arrays (a
// random packing is generated in random order, largest first). In a quasi-static study bodies
// move by a fraction of a diameter, so one ordering lasts the whole study. Measured (one thread,
// docs/benchmarks.md): Morton 2-3.7x faster than a random order at 32,000-108,000 spheres, but
// 5-10 % slower than the rows of a one-diameter grid that specimen placement uses, so placement
// keeps its rows; this renumbers scenes that come in another order.
#include <cstdint>
#include <vector>

#include "core/Scene.hpp"

namespace trueaniso {

// The Morton code of a point given by its reduced cell coordinates wrapped into [0, 1): 10 bits
// per axis (1024 slices, far finer than a particle in any specimen we make), interleaved z y x.
std::uint32_t mortonCode(const Vec3& reduced);

// The body order along the curve: order[k] is the body that becomes body k. Ties (bodies in one
// slice) keep their index order, so the result is deterministic.
std::vector<int> spaceOrder(const Scene& s);

// Renumbers the bodies (and their members, kept contiguous per body) to `order`, a permutation as
// spaceOrder returns. Contacts keep their history: their member and body indices are mapped, a
// pair whose sides swap (members are listed low index first) has its normal, branch, shear force
// and rolling moment (both on side 2) and image shift negated, and the list is sorted again as the detection
// keeps it, with its incidence lists. The detection is marked stale (its reference positions are
// in the old order).
void reorderBodies(Scene& s, const std::vector<int>& order);

}  // namespace trueaniso
