#pragma once
// The sums a cell controller reads every step (the Love-Weber stress, the affine stiffness and the
// unbalanced force of measure/Stress.hpp), and the scene's record of them from the last force
// evaluation. Measurements ride on the force loop (DESIGN.md section 4): in a step where an engine
// reads them (Engine::readsCellMeasures), the contact loop (dynamics/ContactForces) adds each
// loaded contact's terms right after it computes the contact's force, and the bodies' resultants
// as it sums the threads' force buffers, instead of a second walk over the contacts and bodies. It
// adds them in the blocks of measure/Reduce.hpp, each block's terms in pair (body) order and the
// blocks in their order, as the separate pass (contactMeasures) does: the same bits, on any number
// of threads (tests/cpp/test_fused_measures.cpp).
#include <cmath>

#include "core/Types.hpp"
#include "measure/ContactTerms.hpp"

namespace trueaniso {

// The cell measures' sums over contacts, kCellTerms of them: F (x) L row by row (9), the diagonal
// of Eq. (32) in Voigt order (6) and |F| (1), F the force on body 2, L the branch from body 1 to
// body 2.
constexpr int kCellTerms = 16;

// The kCellTerms terms of a contact into t: F (x) L, the diagonal of Eq. (32)
// (measure/ContactTerms.hpp, operation for operation) and |F|. n is the unit normal, kn the
// contact's k_n (Eq. 5), ratio = k_s / k_n. For a contact without load F and kn are zero, and so is
// every term (+0 or -0): -0 added to any sum leaves its bits (x + -0 = x in round-to-nearest, for
// x = +0 too), and +0 added to a sum that is not -0 does too (no sum of such terms starting at +0
// is -0), so a sum may add every touching contact's terms where the separate pass adds only the
// loaded ones. T is Real (one contact) or a vector of contacts side by side, one a lane
// (measure/CellLanes.hpp: the force loop), each contact's arithmetic the same; sqrt takes a T.
// done(g) is called when terms 4g..4g+3 are in t, so that a caller may add them while the next are
// computed (fewer values held at once).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"  // T a vector: always inlined, never called (CellLanes.hpp)
template <class T, class Sqrt, class Done>
__attribute__((always_inline)) inline void cellTerms(const T& Fx, const T& Fy, const T& Fz, const T& Lx, const T& Ly,
                                                     const T& Lz, const T& nx, const T& ny, const T& nz, const T& kn,
                                                     Real ratio, T* t, Sqrt sqrt, Done done) {
  t[0] = Fx * Lx; t[1] = Fx * Ly; t[2] = Fx * Lz; t[3] = Fy * Lx;
  done(0);
  t[4] = Fy * Ly; t[5] = Fy * Lz; t[6] = Fz * Lx; t[7] = Fz * Ly;
  done(1);
  t[8] = Fz * Lz;
  affineStiffnessTerms<T>(kn, ratio, nx, ny, nz, Lx, Ly, Lz, t + 9);
  done(2);
  t[15] = sqrt(Fx * Fx + Fy * Fy + Fz * Fz);
  done(3);
}
#pragma GCC diagnostic pop

// Running sums of contacts' terms, one for each term, each adding its contacts in their order.
struct CellSums {
  alignas(32) Real sum[kCellTerms] = {};  // +0 each (see cellTerms)
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
  // One contact with N > 0: F, L, n, kn and ratio as cellTerms takes them.
  void addContact(const Vec3& F, const Vec3& L, const Vec3& n, Real kn, Real ratio) {
    Real t[kCellTerms];
    cellTerms<Real>(F.x(), F.y(), F.z(), L.x(), L.y(), L.z(), n.x(), n.y(), n.z(), kn, ratio, t,
                    [](Real x) { return std::sqrt(x); }, [](int) {});
    for (int j = 0; j < kCellTerms; ++j) sum[j] += t[j];
    ++loaded;
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
