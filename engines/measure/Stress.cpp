#include "measure/Stress.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <functional>
#include <limits>

#include "contact/HertzMindlin.hpp"
#include "measure/CellSums.hpp"
#include "measure/Reduce.hpp"

namespace trueaniso {

namespace {

// Mean |resultant force| over bodies over the mean |contact force|: YADE's ratio of the two sums.
Real unbalancedRatio(Real bodySum, int bodies, Real contactSum, long contacts) {
  if (contacts == 0 || contactSum == 0) return std::numeric_limits<Real>::quiet_NaN();
  return (bodySum / bodies) / (contactSum / contacts);
}

Real bodyForceSum(const Scene& s) {
  const Bodies& B = s.bodies;
  return blockSum<Real>(B.size(), 0.0, [&](int b, Real& acc) { acc += B.force[b].norm(); });
}

// The sums over contacts of every cell measure, per block of pairs, as the force loop sums them
// (measure/CellSums.hpp): each measure below is read from them, so all agree to the bit with one
// another and with the force loop's.
CellSums contactSums(const Scene& s) {
  const Contacts& C = s.contacts;
  C.requireEvaluated(s.bodies.size(), "stress");
  const Real ratio = HertzMindlin(s.material).shearToNormal();
  return blockSum<CellSums>(C.size(), CellSums{}, [&](int c, CellSums& acc) {
    if (C.normalForce[c] > 0)
      acc.addContact(C.force(c), C.branch(c), C.normal[c], HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]),
                     ratio);
  });
}

ContactMeasures measuresOf(const Scene& s, const CellSums& sum, Real bodySum) {
  const Real V = s.cell.volume();
  return {sum.stress() / V, sum.stiffness() / V, unbalancedRatio(bodySum, s.bodies.size(), sum.contactForce(), sum.loaded)};
}

}  // namespace

Mat3 loveWeberStress(const Scene& s) { return contactSums(s).stress() / s.cell.volume(); }

Real unbalancedForce(const Scene& s) {
  const CellSums c = contactSums(s);
  return unbalancedRatio(bodyForceSum(s), s.bodies.size(), c.contactForce(), c.loaded);
}

ContactMeasures contactMeasures(const Scene& s) { return measuresOf(s, contactSums(s), bodyForceSum(s)); }

ContactMeasures cellMeasures(const Scene& s) {
  if (s.measured.current(s.step)) return measuresOf(s, s.measured.contacts, s.measured.bodyForce);
  return contactMeasures(s);
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

Vec6 affineStiffness(const Scene& s) { return contactSums(s).stiffness() / s.cell.volume(); }

Vec3 principalStresses(const Mat3& sigma) {
  const Mat3 sym = 0.5 * (sigma + sigma.transpose());
  // The iterative solver: a diagonal tensor gives back its diagonal to the last bit.
  Vec3 p = Eigen::SelfAdjointEigenSolver<Mat3>(sym, Eigen::EigenvaluesOnly).eigenvalues();
  std::sort(p.data(), p.data() + 3, std::greater<Real>());
  return p;
}

}  // namespace trueaniso
