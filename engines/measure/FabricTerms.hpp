#pragma once
// The per-contact terms of the fabric tensors (measure/Fabric.hpp, Eqs. 15-16 and 33-34) and
// their normalisation, apart from any contact container: our scene's pass (fabric()) and the YADE
// plugin's FabricRecorder, which walks YADE's interactions, add the same terms.
#include <cmath>

#include "core/Types.hpp"
#include "measure/Fabric.hpp"

namespace trueaniso {

// Per-block partial sums. Only upper triangles are accumulated and mirrored at the end, so the
// symmetric tensors are symmetric to the last bit (a full outer product rounds w a_i a_j and
// w a_j a_i differently).
struct FabricSums {
  Mat3 R = Mat3::Zero(), H = Mat3::Zero(), B = Mat3::Zero();
  // M's upper triangle packed column by column (45 values): a flat run of same-width loads and
  // stores. Accumulating row by row into the 9x9 matrix compiled to mixed 8/16-byte accesses of
  // the same addresses (store-forwarding stalls in the profile): 0.90 ms against 0.56 ms per call
  // for 11.5k contacts.
  Real Mupper[45] = {};
  Real normalForce = 0;
  long contacts = 0;
  FabricSums& operator+=(const FabricSums& o) {
    R += o.R; H += o.H; B += o.B;
    for (int k = 0; k < 45; ++k) Mupper[k] += o.Mupper[k];
    normalForce += o.normalForce; contacts += o.contacts;
    return *this;
  }

  static void addUpperOuter(Mat3& T, const Vec3& a, Real w) {
    for (int i = 0; i < 3; ++i) {
      const Real wa = w * a[i];
      for (int j = i; j < 3; ++j) T(i, j) += wa * a[j];
    }
  }

  // One contact carrying N > 0 with unit normal n, branch L and rbar of Eq. (7). The weight
  // rbar^(1/3) N^(1/3) of Eqs. (33)-(34) is k_n / C_n of Eq. (5): B and M carry the
  // stress-dependent part of the contact stiffness, the material constants stay outside.
  void add(Real N, Real rbar, const Vec3& n, const Vec3& L) {
    const Real w = std::cbrt(rbar * N);
    addUpperOuter(R, n, 1.0);
    addUpperOuter(H, L, 1.0);
    addUpperOuter(B, L, w);
    Eigen::Matrix<Real, 9, 1> u;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) u[pairIndex(i, j)] = L[i] * n[j];
    Real* m = Mupper;
    for (int b = 0; b < 9; ++b) {
      const Real wu = w * u[b];
      for (int a = 0; a <= b; ++a) *m++ += u[a] * wu;
    }
    normalForce += N;
    ++contacts;
  }

  // The averages over the contacts: R, H, B, M and the mean normal force of f (NaN without
  // contacts), and f.counts.contacts.
  void finish(Fabric& f) const {
    Mat9 Mfull;
    for (int b = 0, k = 0; b < 9; ++b)
      for (int a = 0; a <= b; ++a, ++k) Mfull(a, b) = Mfull(b, a) = Mupper[k];
    Mat3 r = R, h = H, bt = B;
    mirror(r); mirror(h); mirror(bt);
    const Real inv = contacts > 0 ? 1.0 / contacts : std::nan("");
    f.counts.contacts = contacts;
    f.R = r * inv;
    f.H = h * inv;
    f.B = bt * inv;
    f.M = Mfull * inv;
    f.meanNormalForce = normalForce * inv;
  }

 private:
  static void mirror(Mat3& T) {
    for (int i = 0; i < 3; ++i)
      for (int j = i + 1; j < 3; ++j) T(j, i) = T(i, j);
  }
};

}  // namespace trueaniso
