#pragma once
// The cell measures' terms (measure/CellSums.hpp) of four contacts side by side, and their running
// sums, for the force loop (dynamics/ContactForces.cpp). Four lanes of a GCC vector: one AVX
// register on x86-64-v3, two SSE2 registers on the baseline. Each lane does the arithmetic of one
// contact alone (cellTerms), and the sums add the four contacts one after the other, in their
// order: the bits of CellSums::addContact contact after contact.
//
// Included by the hot loops' sources only, and every function here is always inlined: a 32-byte
// vector passed between functions compiled for different levels would change the calling
// convention (GCC's -Wpsabi note on the baseline, silenced here), so none is ever called.
#include <cmath>

#include "measure/CellSums.hpp"

#if defined(__AVX__)
#include <immintrin.h>
#endif

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace trueaniso {

constexpr int kLanes = 4;
typedef Real Lanes __attribute__((vector_size(kLanes * sizeof(Real))));
typedef decltype(Lanes{} > Lanes{}) LaneMask;  // a comparison's result: all bits set (true) or none

#define TRUEANISO_LANES_INLINE __attribute__((always_inline)) inline

TRUEANISO_LANES_INLINE Lanes loadLanes(const Real* p) {
  Lanes v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}

// Four 3-vectors stored one after the other (x y z x y z ...: an array of Vec3) by component, the
// twelve values in three loads and rearranged in registers.
TRUEANISO_LANES_INLINE void loadVectorLanes(const Real* p, Lanes& x, Lanes& y, Lanes& z) {
  const Lanes a = loadLanes(p), b = loadLanes(p + 4), c = loadLanes(p + 8);  // x0 y0 z0 x1, y1 z1 x2 y2, z2 x3 y3 z3
  const Lanes xs = __builtin_shufflevector(a, b, 0, 3, 6, 7);  // x0 x1 x2 y2
  const Lanes ys = __builtin_shufflevector(a, b, 1, 4, 7, 5);  // y0 y1 y2 z1
  const Lanes zs = __builtin_shufflevector(a, b, 2, 5, 4, 4);  // z0 z1 y1 y1
  x = __builtin_shufflevector(xs, c, 0, 1, 2, 5);
  y = __builtin_shufflevector(ys, c, 0, 1, 2, 6);
  z = __builtin_shufflevector(zs, c, 0, 1, 4, 7);
}

// x where the mask is set, else +0.
TRUEANISO_LANES_INLINE Lanes pick(const LaneMask& m, const Lanes& x) { return (Lanes)((LaneMask)x & m); }

TRUEANISO_LANES_INLINE Lanes sqrtLanes(const Lanes& x) {
#if defined(__AVX__)
  return (Lanes)_mm256_sqrt_pd((__m256d)x);
#else
  Lanes r;
  for (int l = 0; l < kLanes; ++l) r[l] = std::sqrt(x[l]);
  return r;
#endif
}

struct SqrtLanes {  // sqrtLanes for cellTerms
  TRUEANISO_LANES_INLINE Lanes operator()(const Lanes& x) const { return sqrtLanes(x); }
};

// Running sums of the terms of contacts given four at a time: sums[g] holds the sums of terms
// 4g..4g+3, counted the contacts with N > 0 (lane by lane, a true mask counting -1).
struct CellLaneSums {
  Lanes sums[kCellTerms / kLanes] = {};  // +0 each
  LaneMask counted = {};

  // Four contacts' terms 4g..4g+3 (t[j]: term j of the four) added, contact by contact: the four
  // terms transposed in registers, so that one vector addition adds one contact's four terms.
  TRUEANISO_LANES_INLINE void addGroup(int g, const Lanes* t) {
    const Lanes &a = t[4 * g], &b = t[4 * g + 1], &c = t[4 * g + 2], &d = t[4 * g + 3];
    const Lanes ab0 = __builtin_shufflevector(a, b, 0, 4, 2, 6), ab1 = __builtin_shufflevector(a, b, 1, 5, 3, 7);
    const Lanes cd0 = __builtin_shufflevector(c, d, 0, 4, 2, 6), cd1 = __builtin_shufflevector(c, d, 1, 5, 3, 7);
    Lanes s = sums[g];
    s += __builtin_shufflevector(ab0, cd0, 0, 1, 4, 5);  // contact 0's terms 4g..4g+3
    s += __builtin_shufflevector(ab1, cd1, 0, 1, 4, 5);  // contact 1's
    s += __builtin_shufflevector(ab0, cd0, 2, 3, 6, 7);  // contact 2's
    s += __builtin_shufflevector(ab1, cd1, 2, 3, 6, 7);  // contact 3's
    sums[g] = s;
  }

  TRUEANISO_LANES_INLINE CellSums cellSums() const {
    CellSums out;
    for (int g = 0; g < kCellTerms / kLanes; ++g)
      for (int l = 0; l < kLanes; ++l) out.sum[kLanes * g + l] = sums[g][l];
    for (int l = 0; l < kLanes; ++l) out.loaded += counted[l];
    return out;
  }
};

// The terms of four contacts (cellTerms on each lane) added to sums: F the contact force, L the
// branch, n the unit normal, N the normal force and delta the overlap, whose k_n is
// HertzMindlin::normalStiffness's. A lane with N <= 0 is a contact without load: its F and k_n are
// taken as zero, so that its terms leave the sums' bits (cellTerms), and it is not counted.
TRUEANISO_LANES_INLINE void addCellTerms(const Lanes& Fx, const Lanes& Fy, const Lanes& Fz, const Lanes& Lx,
                                         const Lanes& Ly, const Lanes& Lz, const Lanes& nx, const Lanes& ny,
                                         const Lanes& nz, const Lanes& N, const Lanes& delta, Real ratio,
                                         CellLaneSums& sums) {
  const Lanes zero = {};
  const LaneMask loaded = N > zero;
  const Lanes kn = pick(loaded & (delta > zero), 1.5 * N / delta);  // normalStiffness: 1.5 N / delta
  Lanes t[kCellTerms];
  cellTerms<Lanes>(pick(loaded, Fx), pick(loaded, Fy), pick(loaded, Fz), Lx, Ly, Lz, nx, ny, nz, kn, ratio, t,
                   SqrtLanes(), [&](int g) __attribute__((always_inline)) { sums.addGroup(g, t); });
  sums.counted -= loaded;  // a true lane is -1
}

// The same for the first `count` (< kLanes) lanes: the others, whatever they hold, are no contact.
TRUEANISO_LANES_INLINE void addCellTermsOf(int count, const Lanes& Fx, const Lanes& Fy, const Lanes& Fz,
                                           const Lanes& Lx, const Lanes& Ly, const Lanes& Lz, const Lanes& nx,
                                           const Lanes& ny, const Lanes& nz, const Lanes& N, const Lanes& delta,
                                           Real ratio, CellLaneSums& sums) {
  const LaneMask lane = {0, 1, 2, 3}, valid = lane < (LaneMask{} + count);
  addCellTerms(Fx, Fy, Fz, pick(valid, Lx), pick(valid, Ly), pick(valid, Lz), pick(valid, nx), pick(valid, ny),
               pick(valid, nz), pick(valid, N), delta, ratio, sums);
}

#undef TRUEANISO_LANES_INLINE

}  // namespace trueaniso

#pragma GCC diagnostic pop
