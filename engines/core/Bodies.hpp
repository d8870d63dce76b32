#pragma once
// Rigid bodies as a structure of arrays. Every body is a clump of >= 1 member spheres, so a free
// sphere is a body with one member at zero offset and clumps need no special case in the loops.
#include <vector>

#include "core/Types.hpp"

namespace trueaniso {

struct Bodies {
  std::vector<Vec3> pos;       // centre of mass, not wrapped into the cell
  std::vector<Vec3> vel;       // fluctuation velocity (total velocity minus the cell's affine field)
  std::vector<Vec3> angVel;    // world frame
  std::vector<Vec3> force;     // contact force of the last force evaluation
  std::vector<Vec3> torque;
  std::vector<Real> mass;
  std::vector<Vec3> inertia;   // principal moments of inertia (body frame)
  // Solid volume: the union of the member balls, overlaps counted once (clump/ClumpTemplate.hpp).
  // The void ratio reads it; it is kept apart from the mass, which a user (or YADE, whose clumps
  // sum their members' masses unless told to integrate) may set otherwise.
  std::vector<Real> volume;
  std::vector<Quat> orientation;  // body frame -> world; only advanced for multi-sphere clumps
  std::vector<int> memberBegin{0};  // members of body b: [memberBegin[b], memberBegin[b+1])

  int size() const { return static_cast<int>(pos.size()); }
  int memberCount(int b) const { return memberBegin[b + 1] - memberBegin[b]; }

  void clear() { *this = Bodies(); }
  void resizeDynamics() {
    vel.resize(pos.size(), Vec3::Zero());
    angVel.resize(pos.size(), Vec3::Zero());
    force.resize(pos.size(), Vec3::Zero());
    torque.resize(pos.size(), Vec3::Zero());
  }
};

// Member spheres. For a scene of single spheres member m belongs to body m and pos[m] is the
// body's position; for clumps pos is refreshed from the body's position and orientation.
struct Members {
  std::vector<int> body;
  std::vector<Vec3> offset;   // in the body frame
  std::vector<Real> radius;
  std::vector<Vec3> pos;      // world position, unwrapped like the body's

  int size() const { return static_cast<int>(body.size()); }
};

}  // namespace trueaniso
