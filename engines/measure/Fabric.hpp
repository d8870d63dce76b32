#pragma once
// Micro-structure of the contact network, in the paper's words (sections 3.2 and 4.2):
// mechanical coordination number Zm (Eq. 14), contact normal fabric R (Eq. 15), branch vector
// fabric H (Eq. 16), branch-contact-stiffness fabric B (Eq. 33), mixed tensor M (Eq. 34), the
// contact density Nc/V (Eq. 36 and direct count), the void ratio and the mean normal force.
//
// A particle is a body: a clump counts once in Np, its branch vectors join clump centres
// (Contacts::branch) and every member-member contact between two different bodies counts in Nc,
// with rbar (Eq. 7) from the two member spheres in contact.
#include <Eigen/Core>

#include "core/Scene.hpp"
#include "measure/Coordination.hpp"

namespace trueaniso {

// A fourth-order tensor T_ijkl stored as a 9x9 matrix over the index pairs: row 3i+j, column
// 3k+l. M of Eq. (34) is then a weighted sum of u u^T with u_(3i+j) = L_i n_j, which makes its
// major symmetry M_ijkl = M_klij the symmetry of this matrix.
using Mat9 = Eigen::Matrix<Real, 9, 9>;

inline int pairIndex(int i, int j) { return 3 * i + j; }

struct Fabric {
  Coordination counts;   // Nc, Np, Np^0, Np^1; counts.mechanical() is Eq. (14)
  Real Zm = 0;           // Eq. (14); NaN when no particle has two contacts
  Mat3 R = Mat3::Zero(); // Eq. (15)
  Mat3 H = Mat3::Zero(); // Eq. (16), m^2
  Mat3 B = Mat3::Zero(); // Eq. (33), m^(7/3) N^(1/3): r^(1/3) N^(1/3) L L
  Mat9 M = Mat9::Zero(); // Eq. (34), same unit as B
  Real meanNormalForce = 0;  // <N> over the Nc contacts (N)
  Real volume = 0;           // cell volume V (m^3)
  Real voidRatio = 0;        // e from the bodies' solid volumes (measure/Coordination.hpp)
  // <r^3> over the Np particles. A clump enters with the radius of the sphere of equal volume,
  // r^3 = 3 V_b / (4 pi) with V_b its union volume: Eq. (36) was derived for spheres, for which
  // V_s = (4/3) pi sum r^3, and this keeps that relation exact, so that Eq. (36) stays consistent
  // with e.
  Real meanRadiusCubed = 0;

  Real M4(int i, int j, int k, int l) const { return M(pairIndex(i, j), pairIndex(k, l)); }
  // Eq. (36) with the mean <r^3> in place of the printed sum over Np particles (the sum is
  // dimensionally the same but Np times too small: Chang et al. (1995) derive it for one radius
  // r, Nc/V = 3 Z / (8 pi (1+e) r^3)). With r^3 from the volumes it equals Zm Np / (2 V).
  Real contactDensityEq36() const;
  // Nc / V, counted.
  Real contactDensityCount() const { return counts.contacts / volume; }
};

// All of the above in one pass over the listed pairs (block sums, thread-count independent).
// The contacts must be those of a force evaluation at the current configuration (they carry n,
// L and N): throws InputError if the list is marked stale or an active contact has no branch.
Fabric fabric(const Scene& scene);

}  // namespace trueaniso
