#pragma once
// The tolerance of a test whose claim is "the same bits" from two code paths (a batch and one
// contact at a time, one fused pass and three sums). The portable baseline build does not fuse
// multiply-adds and both paths do the same operations in the same order: the tolerance is 0. A
// build for x86-64-v3 (TRUEANISO_ARCH, CMakeLists.txt) lets the compiler fuse a multiply and an
// add into one rounding where it chooses, and it chooses differently in the two paths: there the
// claim is agreement in the last digits, relative to the quantity's scale (measured below).
#include "core/Types.hpp"

namespace trueaniso::test {

#ifdef __FMA__
// Largest relative differences measured on the v3 build: 2.6e-16 (a batch's forces against one
// contact's) and 2.9e-17 (the fused affine stiffness against its own sum; the stress and the
// unbalanced force came out equal); 1e-14 is about 40 times the larger.
constexpr Real kSameBits = 1e-14;
#else
constexpr Real kSameBits = 0.0;
#endif

}  // namespace trueaniso::test
