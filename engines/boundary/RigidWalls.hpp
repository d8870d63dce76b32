#pragma once
// Six rigid frictionless walls: the planes x_k = lo_k and x_k = hi_k (k = x, y, z) inside a
// periodic cell that is wider than the walled box, as PFC's and YADE's servo-controlled walls
// bound a specimen. The cell only hosts the contact detection: it is kept fixed (velGrad 0) and
// must exceed the box by more than a diameter plus the detection skin on every axis, so that no
// pair forms across the periodic boundary (validate() checks the margin against the largest
// sphere; the skin is the caller's, docs/cell.md).
//
// A wall contact is a sphere of radius r against a rigid half-space: Hertz with R* = r and the
// contact modulus of a rigid plane against the sphere's material,
//   1/E*_w = (1 - nu^2)/E, E = 2 G (1 + nu)  =>  E*_w = 2 G / (1 - nu) (twice the two-sphere E*),
//   N = (4/3) E*_w sqrt(r) delta^(3/2),  k_n = dN/d delta = 2 E*_w sqrt(r delta) = 1.5 N / delta,
// along the wall's inward normal. Frictionless: no tangential force, so a single sphere gets no
// moment; a clump member does, about the clump's centre. The contacts need no list: every step
// each member sphere is tested against the six planes (O(N)).
//
// The walls are kinematic: each axis moves its pair symmetrically at the engineering strain rate
// `rate` (extension positive): the wall gap L_k changes by rate_k L_k dt per step, half at each
// wall. What drives the rate is a controller's (WallServo below, or the caller).
#include <memory>
#include <string>

#include "control/CellMeasurement.hpp"
#include "control/TrueTriaxialServo.hpp"
#include "core/Engine.hpp"

namespace trueaniso {

class RigidWalls : public Engine {
 public:
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // wall positions (m)
  Vec3 refWidth = Vec3::Ones();               // gaps at zero strain (setBox)
  Vec3 rate = Vec3::Zero();                   // engineering strain rate per axis (1/s, extension > 0)

  // Of the last force evaluation, per wall in the order (x lo, x hi, y lo, y hi, z lo, z hi):
  Vec6 force = Vec6::Zero();      // normal force the spheres exert on the wall (N, > 0 pushing it out)
  Vec6 stiffness = Vec6::Zero();  // sum of the wall's contact stiffnesses k_n (N/m)
  Eigen::Matrix<long, 6, 1> contacts = Eigen::Matrix<long, 6, 1>::Zero();  // spheres touching it
  Real maxOverlap = 0;            // largest wall overlap over all walls (m)

  // Walls at lo and hi, the reference gaps hi - lo, the rate zero.
  void setBox(const Vec3& lower, const Vec3& upper);
  Vec3 width() const { return hi - lo; }
  Real area(int axis) const;      // of the walls normal to `axis`: the product of the other two gaps
  Real boxVolume() const { return width().prod(); }
  // Mean of the two walls' forces over their area, per axis (Pa, compression positive).
  Vec3 stress() const;
  // For a cell controller (TrueTriaxialServo::update): the wall stresses on the diagonal (no shear:
  // the walls transmit none), the box's deformation diag(L / L_ref), the stiffness
  // dsigma_k / d(-strain_k) of the wall contacts alone, (K_lo + K_hi) L_k / (4 A_k) (each wall moves
  // by strain L_k / 2; an upper bound of the specimen's response, which is softer, so the loop
  // under-corrects and stays stable), and the unbalanced force of the scene (wall forces included
  // in the bodies' resultants).
  CellMeasurement measurement(const Scene& scene) const;
  // The Hertz force of one sphere against a wall (above).
  static Real normalForce(const Material& m, Real radius, Real overlap);

  // Throws InputError for an unusable setup: inverted or non-finite walls, a cell that is not a
  // fixed orthorhombic box, or walls closer to a cell face than the largest diameter plus `margin`.
  void validate(const Scene& scene) const;
  Real margin = 0;  // m: the detection skin the caller keeps on top of the largest diameter

  // Moves the walls by the rate over the step, then adds the wall forces to the bodies.
  void apply(Scene& scene) override;
  std::string name() const override { return "RigidWalls"; }
  // The wall forces of the current positions added to the bodies (no motion of the walls).
  void addForces(Scene& scene);
};

// Drives the walls along a true-triaxial path with the cell servo's logic (TrueTriaxialServo
// with controlShear off: the path, its goal's motion, the hold and failure criteria are the same
// code), fed with the walls' measurement; the strain rates it returns move the walls instead of
// the cell. Runs after RigidWalls in the engine list.
class WallServo : public Engine {
 public:
  WallServo(std::shared_ptr<RigidWalls> walls, std::shared_ptr<TrueTriaxialServo> path);
  std::shared_ptr<RigidWalls> walls;
  std::shared_ptr<TrueTriaxialServo> path;

  // Checks the path (no shear control: walls carry no shear) and sets its loading friction on
  // the scene (TrueTriaxialServo::start). Required before running.
  void start(Scene& scene);
  void apply(Scene& scene) override;
  std::string name() const override { return "WallServo"; }
};

}  // namespace trueaniso
