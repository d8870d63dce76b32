#pragma once
// The sums a cell controller reads every step (the Love-Weber stress, the affine stiffness and the
// unbalanced force of measure/Stress.hpp), and the scene's record of them from the last force
// evaluation. Measurements ride on the force loop (DESIGN.md section 4): in a step where an engine
// reads them (Engine::readsCellMeasures), the contact loop (dynamics/ContactForces) adds each
// loaded contact's terms right after it computes the contact's force, and the bodies' resultants
// as it sums the threads' force buffers, instead of a second walk over the contacts and bodies. It
// adds them in the blocks of measure/Reduce.hpp, each block's terms in pair (body) order and the
// blocks in their order, as the separate pass (contactMeasures) does: the same bits, on any number
// of threads (tests/cpp/test_dynamics.cpp, "FusedMeasures...").
#include <cmath>

#include "core/Types.hpp"
#include "measure/ContactTerms.hpp"

namespace trueaniso {

// The cell measures' sums over contacts, kCellTerms of them: F (x) L row by row (9), the diagonal
// of Eq. (32) in Voigt order (6) and |F| (1), F the force on body 2, L the branch from body 1 to
// body 2.
constexpr int kCellTerms = 16;

// The kCellTerms terms of a contact into column k of rows of terms (a row a term): F (x) L, the
// diagonal of Eq. (32) (measure/ContactTerms.hpp, operation for operation) and |F|, for a contact
// with load (N > 0); zeros for one without. n is the unit normal, kn the contact's k_n (Eq. 5; 0
// for a contact without stiffness, whose Eq. (32) terms are then zeros), ratio = k_s / k_n. Adding
// a zero to a running sum that started at +0 leaves its bits (in round-to-nearest no sum of such
// terms is -0), so a sum may add every contact's column where the separate pass adds only the
// loaded ones. On scalars and without a branch, so that a loop over contacts runs it several
// contacts at a time (vector lanes; dynamics/ContactForces.cpp), each contact's arithmetic that of
// one alone.
template <int Columns>
__attribute__((always_inline)) inline void cellTermsColumn(Real Fx, Real Fy, Real Fz, Real Lx, Real Ly, Real Lz,
                                                           Real nx, Real ny, Real nz, bool loaded, Real kn, Real ratio,
                                                           Real (*terms)[Columns], int k) {
  terms[0][k] = loaded ? Fx * Lx : 0.0; terms[1][k] = loaded ? Fx * Ly : 0.0; terms[2][k] = loaded ? Fx * Lz : 0.0;
  terms[3][k] = loaded ? Fy * Lx : 0.0; terms[4][k] = loaded ? Fy * Ly : 0.0; terms[5][k] = loaded ? Fy * Lz : 0.0;
  terms[6][k] = loaded ? Fz * Lx : 0.0; terms[7][k] = loaded ? Fz * Ly : 0.0; terms[8][k] = loaded ? Fz * Lz : 0.0;
  Real K[6];
  affineStiffnessTerms(loaded ? kn : 0.0, ratio, nx, ny, nz, Lx, Ly, Lz, K);
  for (int I = 0; I < 6; ++I) terms[9 + I][k] = K[I];
  terms[15][k] = loaded ? std::sqrt(Fx * Fx + Fy * Fy + Fz * Fz) : 0.0;
}

// Running sums of contacts' terms, one for each term, each adding its contacts in their order.
struct CellSums {
  alignas(32) Real sum[kCellTerms] = {};  // +0 each (see cellTermsColumn)
  long loaded = 0;                        // contacts with N > 0

  Mat3 stress() const {  // sum of F (x) L over the loaded contacts
    Mat3 m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) m(i, j) = sum[3 * i + j];
    return m;
  }
  Vec6 stiffness() const { return Eigen::Map<const Vec6>(sum + 9); }  // sum of Eq. (32)'s diagonal
  Real contactForce() const { return sum[15]; }                       // sum of |F| over the loaded contacts

  CellSums& operator+=(const CellSums& o) {
    for (int j = 0; j < kCellTerms; ++j) sum[j] += o.sum[j];
    loaded += o.loaded;
    return *this;
  }
  // One contact with N > 0: F, L, n, kn and ratio as cellTermsColumn takes them.
  void addContact(const Vec3& F, const Vec3& L, const Vec3& n, Real kn, Real ratio) {
    Real t[kCellTerms][1];
    cellTermsColumn(F.x(), F.y(), F.z(), L.x(), L.y(), L.z(), n.x(), n.y(), n.z(), true, kn, ratio, t, 0);
    for (int j = 0; j < kCellTerms; ++j) sum[j] += t[j][0];
    ++loaded;
  }
  // Columns 0..m-1 of rows of terms (cellTermsColumn), column after column: each sum adds its
  // contacts in their order, the sixteen sums side by side.
  template <int Columns>
  __attribute__((always_inline)) void addColumns(const Real (*terms)[Columns], int m) {
    for (int k = 0; k < m; ++k)
      for (int j = 0; j < kCellTerms; ++j) sum[j] += terms[j][k];
  }
};

// What the force evaluation of one step summed (Scene::measured).
struct MeasuredSums {
  // Sum in the next force evaluation: set before every step by the simulation, true when an engine
  // that runs in the step reads the measures.
  bool wanted = false;
  long step = -1;       // the step (Scene::step) of the force evaluation that filled the sums; -1: none
  CellSums contacts;
  Real bodyForce = 0;   // sum over the bodies of |resultant force|

  // Valid for the scene's current step: filled by this step's force evaluation and not made stale
  // since (anything that changes the bodies' forces outside the contact loop calls clear()).
  bool current(long sceneStep) const { return step >= 0 && step == sceneStep; }
  void clear() { step = -1; }
};

}  // namespace trueaniso
