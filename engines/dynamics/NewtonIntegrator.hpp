#pragma once
// Leap-frog integration of body motion with the local non-viscous damping of YADE's
// NewtonIntegrator (each acceleration component scaled by 1 -/+ damping against the velocity; for
// clumps the torque, as YADE's aspherical integrator), plus the cell's deformation: positions
// follow the affine field of the cell's velocity gradient (x -> (I + dt L) x, the cell vectors
// too) and velocities are stored as fluctuations about it. Clumps rotate by an
// angular-momentum-conserving splitting (NewtonIntegrator.cpp).
#include "core/Engine.hpp"

namespace trueaniso {

class NewtonIntegrator : public Engine {
 public:
  Real damping = 0.2;  // YADE's default
  // The step is checked against the two-body stability limit of every contact at least every
  // `checkEvery` steps, and at once when it comes above half the limit last found; an unstable
  // step is refused with an error.
  long checkEvery = 100;

  void apply(Scene& scene) override;
  std::string name() const override { return "NewtonIntegrator"; }

 private:
  template <bool Rotations, bool Clumps>
  void integrate(Scene& scene) const;
  static constexpr int kClumpLanes = 4;  // clumps rotated side by side (NewtonIntegrator.cpp)
  static void advanceClumps(Bodies& bodies, const int* b, int count, Real dt, Real damping);
  void checkStability(const Scene& scene);
  Real checkedLimit_ = 0;
  long checkedStep_ = -1;
};

}  // namespace trueaniso
