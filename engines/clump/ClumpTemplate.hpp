#pragma once
// A clump template: a rigid union of overlapping member balls, with the mass properties of the
// union (overlaps counted once) from CGAL (UnionOfBalls.hpp), computed once and then scaled and
// rotated for every clump of that shape.
//
// The template's frame is the union's principal frame: origin at its centroid, axes along its
// principal axes of inertia in ascending order of moment (as YADE's Clump::updateProperties),
// right-handed. A clump is then placed by a position (its centre of mass) and an orientation
// (template frame -> world), and its inertia is diagonal in its own frame, which is what
// NewtonIntegrator's Euler equations use.
#include <vector>

#include "core/Types.hpp"

namespace trueaniso {

struct ClumpTemplate {
  std::vector<Vec3> offsets;  // member centres in the template frame
  std::vector<Real> radii;
  Real volume = 0;            // solid volume of the union (m^3)
  Vec3 inertia = Vec3::Zero();  // principal moments per unit density (m^5), ascending
  // Where the members were given: member k was at centroid + axes * offsets[k] (axes: rotation).
  Vec3 centroid = Vec3::Zero();
  Mat3 axes = Mat3::Identity();
  Real volumeErrorEstimate = 0;  // UnionOfBalls.hpp; 0 for one member (closed form)

  int size() const { return static_cast<int>(radii.size()); }
  // Largest distance from the centroid to a member surface.
  Real boundingRadius() const;
  // Diameter of the sphere of the same volume: the size a clump has in a size distribution.
  Real equivalentDiameter() const;
  // The same shape with every length times f (volume f^3, moments f^5).
  ClumpTemplate scaled(Real f) const;
};

// Throws InputError, before any geometry is computed, for: no member, mismatched lengths,
// a radius that is not a finite number > 0, a centre that is not finite, or members whose balls
// do not overlap into one connected body (each member must overlap another, strictly: touching
// at a point is not one rigid body of finite strength).
void validateClumpMembers(const std::vector<Vec3>& centres, const std::vector<Real>& radii);

// A template from member centres and radii in any frame (validated first).
ClumpTemplate makeClumpTemplate(const std::vector<Vec3>& centres, const std::vector<Real>& radii, int levels = 4);

// Solid volume of the union of the members, cached: clumps of one shape (members equal up to a
// rigid motion and a scale, recognised by their scale-free distance matrix) cost one CGAL
// computation per shape, which is what a specimen file or a YADE scene of thousands of clumps of
// a few templates needs when it is loaded. Validates the members.
Real cachedClumpVolume(const std::vector<Vec3>& centres, const std::vector<Real>& radii);

}  // namespace trueaniso
