#pragma once
// Exact static stiffness of the contact network at a held state.
//
// What it computes: the tangent C = d sigma / d eps (6x6 Voigt, xx yy zz yz xz xy) of the
// Love-Weber stress sigma = (1/V) sum F (x) L (compression positive, the symmetric part) against the
// cell's strain eps (compression positive: eps_k = -ln(h_k/h_ref), engineering shears), with every
// contact sticking and every load-carrying body in force (and, unless rotations are blocked,
// moment) equilibrium after the increment. The contact law is linearised exactly as the dynamic
// law acts (ContactTangent.hpp), including the terms of the existing forces (frame rotation,
// N dn, lever arms, F dL, the volume change). This is the limit a quasi-static stress probe with
// sliding suppressed converges to: to first order in the increment, the probe's Delta sigma is the
// change of this same Love-Weber tensor and its Delta eps the change of this same log strain.
//
// How: DOFs are the bodies' translations and rotations (blocks of 3 or 6), the six strains are
// prescribed; K u = JE e is solved for the six unit strains with a sparse Cholesky factorisation
// of K's symmetric part (CHOLMOD) as preconditioner of iterative refinement, GMRES as fallback,
// for the small non-symmetric part (frame rotation and lever-arm terms of the shear forces), then
// d(sigma V)/de = SE + S u and C = -(d sigma/de) (extension-positive e = -eps).
// Rattlers are removed (Rattlers.hpp) and zero modes pinned (ZeroModes.hpp); both are reported.
#include <string>
#include <vector>

#include "core/Scene.hpp"
#include "theory/Orthotropic.hpp"
#include "statics/Voigt.hpp"
#include "statics/ZeroModes.hpp"

namespace trueaniso {

struct StaticStiffnessResult {
  Mat6 C = Mat6::Zero();           // relaxed tangent stiffness
  Mat6 compliance = Mat6::Zero();  // C^-1 (NaN if C is singular)
  OrthotropicModuli constants;     // E_i, nu_ij (Eqs. 40-42, probe conditions), G_ij (Eq. 39)
  // Affine (kinematic hypothesis) stiffness of every contact, no relaxation and no rotation:
  // affineNormal + affineShear is Eq. (32) (k_n n n and k_s (I - n n) parts of K_jl), and
  // affineGeometric the terms of the existing forces; affine is their sum.
  Mat6 affine = Mat6::Zero(), affineNormal = Mat6::Zero(), affineShear = Mat6::Zero();
  Mat6 affineGeometric = Mat6::Zero();
  Mat3 stress = Mat3::Zero();      // Love-Weber stress of the held state
  Real volume = 0;
  Real unbalancedForce = 0, unbalancedTorque = 0;
  // Solver residual: max over the six strains of ||K u - f|| / ||f|| over the equations solved
  // (||f|| is replaced by the norm of the contacts' affine force increments where the affine field
  // is already in equilibrium, f ~ 0, as in lattices of inversion-symmetric sites).
  Real residual = 0;
  // The same over the pinned DOFs' equations: the reaction that holds them, zero for exact zero
  // modes; nonzero for pinned hinges whose initial-force stiffness is not zero (ZeroModes.hpp).
  Real pinnedReaction = 0;
  int iterations = 0;              // refinement iterations (0: the Cholesky solve was enough)
  int gmresIterations = 0;         // GMRES fallback iterations (0: not needed)
  int factorizations = 0;
  std::vector<int> rattlers;
  std::vector<PinnedDof> pinned;
  bool rotations = true;
  int bodies = 0, dofs = 0, contacts = 0;
  long factorNonzeros = 0;
  double factorFlops = 0;          // of one numeric factorisation
  bool supernodal = false;
  // Wall times (s): held state and balance check, assembly and zero-mode detection, ordering and
  // symbolic analysis, numeric factorisation(s), solves and stress.
  double timeHeld = 0, timeAssembly = 0, timeAnalysis = 0, timeFactorization = 0, timeSolve = 0;
  double timeTotal = 0;
};

class StaticStiffness {
 public:
  bool rotations = true;
  // A probe waits for an unbalanced force of about 1e-4..1e-3; a state an order of magnitude
  // above the consolidation criterion (1e-3) is not at rest.
  Real maxUnbalanced = 1e-2;
  // Zero pivots: below this fraction of their diagonal (exact zero modes give round-off, ~1e-15).
  Real pivotTolerance = 1e-9;
  // Local modes pinned at once: a body's own eigenvalue below this fraction of its block's mean.
  // The hinges of weakly loaded two-contact bodies sit at 1e-10..1e-8 (their stiffness is the
  // initial forces', of either sign, at the level of the state's imbalance); every other local
  // eigenvalue seen on random packings is above 0.1. A hinge stiffer than this stays a DOF.
  Real zeroModeTolerance = 1e-6;
  // Bodies with a local mode below this fraction get their DOFs turned to the mode (ZeroModes.hpp).
  Real softModeTolerance = 1e-2;
  Real tolerance = 1e-12;   // refinement target of the relative residual
  int maxIterations = 200;
  int maxFactorizations = 60;
  bool forceGmres = false;  // skip the refinement (tests of the fallback)

  StaticStiffnessResult compute(const Scene& scene) const;
};

}  // namespace trueaniso
