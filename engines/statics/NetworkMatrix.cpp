#include "statics/NetworkMatrix.hpp"

#include <algorithm>
#include <limits>

#include "statics/ContactTangent.hpp"
#include "statics/HeldState.hpp"

namespace trueaniso {

namespace {

// Bounding radius of a body: the farthest member surface from its centre.
Real bodyScale(const Scene& s, int b) {
  Real r = 0;
  for (int m = s.bodies.memberBegin[b]; m < s.bodies.memberBegin[b + 1]; ++m)
    r = std::max(r, s.members.offset[m].norm() + s.members.radius[m]);
  return r;
}

}  // namespace

NetworkMatrix assembleNetwork(const Scene& held, const std::vector<char>& rattler, bool rotations) {
  require(!held.material.rolling(), "the static solve does not model rolling resistance (no rolling springs in "
                                    "the network matrix)");
  const Contacts& C = held.contacts;
  const int nb = held.bodies.size();
  NetworkMatrix net;
  const int m = net.dofsPerBody = rotations ? 6 : 3;
  net.blockOfBody.assign(nb, -1);
  for (int b = 0; b < nb; ++b)
    if (!rattler[b]) {
      net.blockOfBody[b] = static_cast<int>(net.bodyOfBlock.size());
      net.bodyOfBlock.push_back(b);
      net.rotationScale.push_back(bodyScale(held, b));
      net.frame.push_back(Mat6::Identity());
    }
  const int nblocks = static_cast<int>(net.bodyOfBlock.size());
  const int n = nblocks * m;

  // Block pattern: each block column holds its own block and one per contact neighbour.
  std::vector<std::vector<int>> nbr(nblocks);
  for (int k = 0; k < nblocks; ++k) nbr[k].push_back(k);
  std::vector<int> kept;
  for (int c = 0; c < C.size(); ++c) {
    if (C.normalForce[c] <= 0) continue;
    const int a = net.blockOfBody[C.b1[c]], b = net.blockOfBody[C.b2[c]];
    if (a < 0 || b < 0) continue;
    kept.push_back(c);
    nbr[a].push_back(b);
    nbr[b].push_back(a);
  }
  net.contacts = static_cast<int>(kept.size());
  net.localRatio.assign(static_cast<size_t>(nblocks) * m, std::numeric_limits<Real>::infinity());
  std::vector<long> base(nblocks + 1, 0);
  for (int k = 0; k < nblocks; ++k) {
    std::sort(nbr[k].begin(), nbr[k].end());
    nbr[k].erase(std::unique(nbr[k].begin(), nbr[k].end()), nbr[k].end());
    base[k + 1] = base[k] + static_cast<long>(m) * m * nbr[k].size();
  }
  net.K.resize(n, n);
  net.K.resizeNonZeros(base[nblocks]);
  int* outer = net.K.outerIndexPtr();
  int* inner = net.K.innerIndexPtr();
  Real* val = net.K.valuePtr();
  for (int k = 0; k < nblocks; ++k) {
    const int len = m * static_cast<int>(nbr[k].size());
    for (int col = 0; col < m; ++col) {
      const long start = base[k] + static_cast<long>(col) * len;
      outer[k * m + col] = static_cast<int>(start);
      for (size_t p = 0; p < nbr[k].size(); ++p)
        for (int r = 0; r < m; ++r) inner[start + p * m + r] = nbr[k][p] * m + r;
    }
  }
  outer[n] = static_cast<int>(base[nblocks]);
  std::fill(val, val + base[nblocks], 0.0);
  // Value of K(row block i, column block j) entry (r, col).
  auto entry = [&](int i, int j, int r, int col) -> Real& {
    const auto it = std::lower_bound(nbr[j].begin(), nbr[j].end(), i);
    const long p = it - nbr[j].begin();
    const long len = m * static_cast<long>(nbr[j].size());
    return val[base[j] + col * len + p * m + r];
  };

  net.JE.setZero(n, 6);
  net.S.setZero(6, n);
  std::vector<char> keep(C.size(), 0);
  for (int c : kept) keep[c] = 1;
  for (int c = 0; c < C.size(); ++c) {
    if (C.normalForce[c] <= 0) continue;
    const ContactTangent t = linearise(heldContact(held, c));
    net.SEnormalAll += t.SEnormal;
    net.SEshearAll += t.SEshear;
    net.SEgeometricAll += t.SEgeometric;
    if (!keep[c]) continue;
    net.SE += t.SEnormal + t.SEshear + t.SEgeometric;
    const Eigen::Matrix<Real, 3, 6> dFe = t.JE.block<3, 6>(6, 0);
    net.contactLoadNorm += dFe.colwise().squaredNorm().transpose();
    const int blocks[2] = {net.blockOfBody[C.b1[c]], net.blockOfBody[C.b2[c]]};
    // Local index (0..11) -> scale of that DOF: 1 for translations, 1/s for rotations.
    Real scale[12];
    for (int side = 0; side < 2; ++side)
      for (int k = 0; k < 6; ++k) scale[6 * side + k] = k < 3 ? 1.0 : 1.0 / net.rotationScale[blocks[side]];
    for (int sj = 0; sj < 2; ++sj)
      for (int cj = 0; cj < m; ++cj) {
        const int lj = 6 * sj + cj;
        for (int si = 0; si < 2; ++si)
          for (int ri = 0; ri < m; ++ri) {
            const int li = 6 * si + ri;
            entry(blocks[si], blocks[sj], ri, cj) -= scale[li] * t.J(li, lj) * scale[lj];
          }
        const int dof = blocks[sj] * m + cj;
        net.JE.row(dof) += scale[lj] * t.JE.row(lj);
        net.S.col(dof) += scale[lj] * t.S.col(lj);
      }
  }
  net.contactLoadNorm = net.contactLoadNorm.cwiseSqrt();
  return net;
}

}  // namespace trueaniso
