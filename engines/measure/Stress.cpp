#include "measure/Stress.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <functional>
#include <limits>

#include "contact/HertzMindlin.hpp"
#include "measure/ContactTerms.hpp"
#include "measure/Reduce.hpp"

namespace trueaniso {

namespace {

// One contact's term of each sum. Each measure below and contactMeasures() add the same terms in
// the same blocks (measure/Reduce.hpp), so the fused pass gives the same bits.

// Love-Weber: F_c (x) L_c.
inline void addStress(const Contacts& C, int c, Mat3& acc) {
  if (C.normalForce[c] > 0) addStressTerm(C.force(c), C.branch[c], acc);
}

// The mean contact force of the unbalanced force.
struct ForceMean {
  Real f = 0;
  long n = 0;
  ForceMean& operator+=(const ForceMean& o) { f += o.f; n += o.n; return *this; }
};
inline void addContactForce(const Contacts& C, int c, ForceMean& acc) {
  if (C.normalForce[c] > 0) { acc.f += C.force(c).norm(); ++acc.n; }
}

// The diagonal of Eq. (32), contact springs only.
inline void addAffineStiffness(const Contacts& C, const HertzMindlin& law, int c, Vec6& acc) {
  const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
  if (kn <= 0) return;
  addAffineStiffnessTerm(kn, law.shearToNormal(), C.normal[c], C.branch[c], acc);
}

// Mean |resultant force| over bodies over the mean |contact force|.
Real unbalancedFrom(const Scene& s, const ForceMean& contact) {
  const Bodies& B = s.bodies;
  const Real bodySum = blockSum<Real>(B.size(), 0.0, [&](int b, Real& acc) { acc += B.force[b].norm(); });
  if (contact.n == 0 || contact.f == 0) return std::numeric_limits<Real>::quiet_NaN();
  return (bodySum / B.size()) / (contact.f / contact.n);
}

}  // namespace

Mat3 loveWeberStress(const Scene& s) {
  const Contacts& C = s.contacts;
  const Mat3 sum = blockSum<Mat3>(C.size(), Mat3::Zero(), [&](int c, Mat3& acc) { addStress(C, c, acc); });
  return sum / s.cell.volume();
}

Real unbalancedForce(const Scene& s) {
  const Contacts& C = s.contacts;
  return unbalancedFrom(
      s, blockSum<ForceMean>(C.size(), ForceMean{}, [&](int c, ForceMean& acc) { addContactForce(C, c, acc); }));
}

ContactMeasures contactMeasures(const Scene& s) {
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  struct Sums {
    Mat3 stress = Mat3::Zero();
    Vec6 stiffness = Vec6::Zero();
    ForceMean mean;
    Sums& operator+=(const Sums& o) {
      stress += o.stress;
      stiffness += o.stiffness;
      mean += o.mean;
      return *this;
    }
  };
  const Sums sum = blockSum<Sums>(C.size(), Sums{}, [&](int c, Sums& acc) {
    addStress(C, c, acc.stress);
    addAffineStiffness(C, law, c, acc.stiffness);
    addContactForce(C, c, acc.mean);
  });
  const Real V = s.cell.volume();
  return {sum.stress / V, sum.stiffness / V, unbalancedFrom(s, sum.mean)};
}

Real unbalancedTorque(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  struct Acc {
    Real f = 0, arm = 0;
    long n = 0;
    Acc& operator+=(const Acc& o) { f += o.f; arm += o.arm; n += o.n; return *this; }
  };
  const Acc contact = blockSum<Acc>(C.size(), Acc{}, [&](int c, Acc& acc) {
    if (C.normalForce[c] <= 0) return;
    acc.f += C.force(c).norm();
    acc.arm += s.members.radius[C.m1[c]] + s.members.radius[C.m2[c]] - C.overlap[c];
    ++acc.n;
  });
  if (contact.n == 0 || contact.f == 0) return std::numeric_limits<Real>::quiet_NaN();
  const Real torqueSum = blockSum<Real>(B.size(), 0.0, [&](int b, Real& acc) { acc += B.torque[b].norm(); });
  return (torqueSum / B.size()) / ((contact.f / contact.n) * 0.5 * (contact.arm / contact.n));
}

Vec6 affineStiffness(const Scene& s) {
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  const Vec6 sum =
      blockSum<Vec6>(C.size(), Vec6::Zero(), [&](int c, Vec6& acc) { addAffineStiffness(C, law, c, acc); });
  return sum / s.cell.volume();
}

Vec3 principalStresses(const Mat3& sigma) {
  const Mat3 sym = 0.5 * (sigma + sigma.transpose());
  // The iterative solver: a diagonal tensor gives back its diagonal to the last bit.
  Vec3 p = Eigen::SelfAdjointEigenSolver<Mat3>(sym, Eigen::EigenvaluesOnly).eigenvalues();
  std::sort(p.data(), p.data() + 3, std::greater<Real>());
  return p;
}

}  // namespace trueaniso
