#pragma once
// How far into Hertz's range a packing sits at a given stress: the mean overlap over the radius,
// delta/R, that the mean contact force of equal spheres gives. Hertz's law is the small-overlap
// solution of two elastic spheres; a stress whose overlaps reach a sizeable fraction of the radius
// is outside the law the paper (and this toolkit) models, so the scripts refuse it before any work.
#include "core/Material.hpp"
#include "core/Types.hpp"

namespace trueaniso {

// Equal spheres of radius R at mean stress p, solid fraction phi, coordination number Z:
//  - Love-Weber stress with branch length 2R: p = phi Z <f> / (4 pi R^2), so <f> = 4 pi R^2 p / (phi Z);
//  - Hertz for two spheres of radius R: f = (4/3) E* sqrt(R/2) delta^(3/2);
//  - hence (delta/R)^(3/2) = 3 sqrt(2) pi p / (phi Z E*), independent of R.
// Exact where every contact carries one force (FCC under isotropic stress); for a random packing
// the mean overlap is at most this (delta ~ f^(2/3) is concave).
Real hertzOverlapRatio(const Material& m, Real pressure, Real solidFraction, Real coordination);

// The largest estimated delta/R the scripts accept: at 0.05 the contact radius is already
// sqrt(delta R / 2) = 0.16 R, where Hertz's half-space assumption starts to fail. For the paper's
// material (G 18 GPa, nu 0.15) in a dense packing (phi 0.63, Z 6) that is about 67 MPa, 670 times
// the paper's 100 kPa.
constexpr Real kMaxOverlapRatio = 0.05;

}  // namespace trueaniso
