#pragma once
// Zero modes of a held contact network, made explicit and pinned (the DOF's row and column are
// decoupled, its displacement is zero). Pinning a DOF with a component along an exact zero mode v
// of a symmetric K changes nothing physical: the reduced system is regular, and the pinned row's
// residual is zero because v^T (K u - f) = -v^T f = 0 for a load that does no work on v. The
// full-system residual reported by the solve checks that claim for every pinned DOF.
//  - Global translation of the periodic network: three DOFs of one body.
//  - Local modes: motions of one body, its neighbours held, that its contacts resist only through
//    the initial forces. A body with two contacts has one: the rotation about the line through
//    its two contact points (a "hinge"), which moves neither contact point; when the contacts are
//    diametrically opposed the hinge passes through the centre and is an exact zero mode (a
//    "spin"). Found from each body's own (symmetric) block: a body with an eigenvalue below
//    softTolerance x its mean has its DOFs turned to that block's eigenvectors, so that the mode
//    is one DOF; eigenvalues below zeroTolerance are pinned at once. A soft mode whose initial-
//    force stiffness is negative (an unstable hinge) then shows as a non-positive pivot of that
//    very DOF and is pinned there: the body is held in place, as the probe's transient leaves it.
//  - Collective zero modes (e.g. the counter-rotating "gear" rows of a simple cubic lattice):
//    found as zero pivots of the Cholesky factorisation of the symmetric part, pinned, refactorised.
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "statics/NetworkMatrix.hpp"
#include "statics/SparseCholesky.hpp"

namespace trueaniso {

struct PinnedDof {
  int dof = -1;
  int body = -1;
  // The motion pinned: translation (m) and rotation (rad) of the body, unit norm in the scaled
  // DOFs (rotations times the body's radius).
  Vec3 translation = Vec3::Zero(), rotation = Vec3::Zero();
  std::string reason;  // "global translation", "local zero mode", "non-positive pivot", "zero pivot"
  Real ratio = 0;      // eigenvalue or pivot relative to the DOF's own stiffness (NaN: not positive)
};

// Pins the three translations of the body whose translational stiffness is largest (among the
// bodies whose DOFs were not turned).
std::vector<PinnedDof> pinGlobalTranslation(const NetworkMatrix& net);

// Detects local modes (see above), turns those bodies' DOFs to the eigenvectors of their block
// (K, JE and S transformed, NetworkMatrix::frame set) and returns the DOFs to pin at once.
std::vector<PinnedDof> rotateLocalModes(NetworkMatrix& net, Real zeroTolerance, Real softTolerance);

// K with pinned rows and columns set to zero, their diagonal kept (or the mean diagonal if <= 0).
Eigen::SparseMatrix<Real> pinnedCopy(const Eigen::SparseMatrix<Real>& K, const std::vector<char>& pinned);

// Lower triangle of the symmetric part of the pinned K: what the Cholesky factorisation sees.
Eigen::SparseMatrix<Real> pinnedSymmetricLower(const Eigen::SparseMatrix<Real>& K, const std::vector<char>& pinned);

// Factorises the symmetric part of the pinned K and repeats after pinning: a pivot below
// tolerance x its diagonal pins that DOF; a non-positive pivot pins the softest unpinned local
// mode (localRatio < softTolerance) anywhere, else the failing DOF.
// Throws InputError after maxRounds factorisations (the network is then a mechanism, not a solid).
std::vector<PinnedDof> factorizeWithPins(SparseCholesky& chol, const NetworkMatrix& net, std::vector<char>& pinned,
                                         Real tolerance, Real softTolerance, int maxRounds, int* rounds);

}  // namespace trueaniso
