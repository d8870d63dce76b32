#pragma once
// Assembly of the tangent of a held contact network: one block of DOFs per load-carrying body
// (3 translations, and 3 rotations unless they are blocked), the 6 macroscopic strains of the
// periodic cell as prescribed DOFs, and the Love-Weber stress as output rows.
//
// Rotation DOFs are scaled by a length of their body (the bounding radius s): theta~ = s theta,
// and the moment equations by 1/s, so every DOF is a length, every equation a force, and the
// symmetric part keeps its symmetry; this only conditions the matrix.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "core/Scene.hpp"
#include "statics/Voigt.hpp"

namespace trueaniso {

struct NetworkMatrix {
  int dofsPerBody = 0;                   // 3 or 6
  std::vector<int> blockOfBody;          // -1 for rattlers
  std::vector<int> bodyOfBlock;
  std::vector<Real> rotationScale;       // s per block
  // Per block: the body's scaled motion [u, s theta] = frame * (its DOFs); identity unless the
  // DOFs were turned to the eigenvectors of a local mode (ZeroModes.hpp). Top-left m x m used.
  std::vector<Mat6> frame;
  // Per DOF: its eigenvalue relative to its body's block mean where the block was turned to a
  // local mode, +inf elsewhere (ZeroModes.hpp).
  std::vector<Real> localRatio;
  Eigen::SparseMatrix<Real> K;           // -dR/dq, R the bodies' resultants; not symmetric
  Eigen::MatrixXd JE;                    // dR/de: the out-of-balance load of each unit strain
  Eigen::Matrix<Real, 6, Eigen::Dynamic> S;  // d(sigma V)/dq (Voigt rows)
  Mat6 SE = Mat6::Zero();                // d(sigma V)/de of the contacts between bodies kept
  // Affine stiffness pieces over every contact (rattlers' too), d(sigma V)/de:
  Mat6 SEnormalAll = Mat6::Zero(), SEshearAll = Mat6::Zero(), SEgeometricAll = Mat6::Zero();
  Vec6 contactLoadNorm = Vec6::Zero();   // sqrt(sum_c |dF_c|^2) of each unit strain, kept contacts
  int contacts = 0;                      // contacts in K

  int size() const { return static_cast<int>(K.rows()); }
  int firstDof(int block) const { return block * dofsPerBody; }
};

NetworkMatrix assembleNetwork(const Scene& held, const std::vector<char>& rattler, bool rotations);

}  // namespace trueaniso
