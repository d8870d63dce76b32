#include "measure/Stress.hpp"

#include <limits>

#include "contact/HertzMindlin.hpp"
#include "measure/Reduce.hpp"

namespace trueaniso {

Mat3 loveWeberStress(const Scene& s) {
  const Contacts& C = s.contacts;
  const Mat3 sum = blockSum<Mat3>(C.size(), Mat3::Zero(), [&](int c, Mat3& acc) {
    if (C.normalForce[c] > 0) acc.noalias() += C.force(c) * C.branch[c].transpose();
  });
  return sum / s.cell.volume();
}

Real unbalancedForce(const Scene& s) {
  const Bodies& B = s.bodies;
  const Contacts& C = s.contacts;
  const Real bodySum = blockSum<Real>(B.size(), 0.0, [&](int b, Real& acc) { acc += B.force[b].norm(); });
  struct Acc {
    Real f = 0;
    long n = 0;
    Acc& operator+=(const Acc& o) { f += o.f; n += o.n; return *this; }
  };
  const Acc contact = blockSum<Acc>(C.size(), Acc{}, [&](int c, Acc& acc) {
    if (C.normalForce[c] > 0) { acc.f += C.force(c).norm(); ++acc.n; }
  });
  if (contact.n == 0 || contact.f == 0) return std::numeric_limits<Real>::quiet_NaN();
  return (bodySum / B.size()) / (contact.f / contact.n);
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

Vec3 affineAxialStiffness(const Scene& s) {
  const Contacts& C = s.contacts;
  const HertzMindlin law(s.material);
  const Vec3 sum = blockSum<Vec3>(C.size(), Vec3::Zero(), [&](int c, Vec3& acc) {
    const Real kn = HertzMindlin::normalStiffness(C.normalForce[c], C.overlap[c]);
    if (kn <= 0) return;
    const Real ks = law.shearStiffness(kn);
    const Vec3& n = C.normal[c];
    const Vec3& L = C.branch[c];
    for (int k = 0; k < 3; ++k) {
      // K_kk = sum L_k^2 [k_s + (k_n - k_s) n_k^2], the kk kk component of Eq. (32).
      acc[k] += L[k] * L[k] * (ks + (1.0 - law.shearToNormal()) * kn * n[k] * n[k]);
    }
  });
  return sum / s.cell.volume();
}

}  // namespace trueaniso
