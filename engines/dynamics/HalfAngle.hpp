#pragma once
#include <cmath>

#include "core/Types.hpp"

namespace trueaniso {

// cos and sin of a sub-step's half angle. In a packing nearly every one lies below 2^-27 (99.7 % of
// 1000 clump2 clumps at rest, a spin of 0.03 rad/s over 4e-8 s), where cos rounds to 1 and sin to the
// angle itself (their series' next terms are below half an ulp): what a correctly rounded sin and
// cos return there, and glibc's first branch does, without the cost of the call (6 % of a clump2
// step). Not inlined: inlined, the branch changes how GCC fuses the quaternion products' multiplies
// and adds at x86-64-v3 (FMA), and with them the last bits of every clump run; a call, as the
// library's is, leaves them as the library's sincos gives them.
__attribute__((noinline)) inline void halfAngleCosSin(Real half, Real& c, Real& s) {
  if (std::abs(half) < 0x1p-27) {
    c = 1.0;
    s = half;
    return;
  }
  c = std::cos(half);
  s = std::sin(half);
}

}  // namespace trueaniso
