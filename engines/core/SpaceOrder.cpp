#include "core/SpaceOrder.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace trueaniso {

namespace {

// The 10 low bits of v spread to every third bit (bit i -> bit 3i).
std::uint32_t spreadBits(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

template <class T>
void permute(std::vector<T>& v, const std::vector<int>& order) {
  if (v.size() != order.size()) return;  // an array not allocated yet (e.g. forces before a step)
  std::vector<T> out(v.size());
  for (size_t k = 0; k < order.size(); ++k) out[k] = v[order[k]];
  v.swap(out);
}

}  // namespace

std::uint32_t mortonCode(const Vec3& reduced) {
  std::uint32_t code = 0;
  for (int k = 0; k < 3; ++k) {
    const Real f = reduced[k] - std::floor(reduced[k]);  // wrapped into [0, 1)
    const auto slice = static_cast<std::uint32_t>(std::min<Real>(1023.0, std::max<Real>(0.0, f * 1024.0)));
    code |= spreadBits(slice) << k;
  }
  return code;
}

std::vector<int> spaceOrder(const Scene& s) {
  const int nb = s.bodies.size();
  const Mat3 hinv = s.cell.hSize.inverse();
  std::vector<std::uint32_t> code(nb);
  for (int b = 0; b < nb; ++b) code[b] = mortonCode(hinv * s.bodies.pos[b]);
  std::vector<int> order(nb);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return code[a] < code[b]; });
  return order;
}

void reorderBodies(Scene& s, const std::vector<int>& order) {
  Bodies& B = s.bodies;
  Members& M = s.members;
  const int nb = B.size();
  require(static_cast<int>(order.size()) == nb, "a body order must list every body once");
  std::vector<int> newBody(nb, -1);
  for (int k = 0; k < nb; ++k) {
    require(order[k] >= 0 && order[k] < nb && newBody[order[k]] < 0, "a body order must list every body once");
    newBody[order[k]] = k;
  }

  // Members follow their bodies, each body's members in their old order.
  std::vector<int> memberOrder;
  memberOrder.reserve(M.size());
  std::vector<int> begin(1, 0);
  for (int k = 0; k < nb; ++k) {
    for (int m = B.memberBegin[order[k]]; m < B.memberBegin[order[k] + 1]; ++m) memberOrder.push_back(m);
    begin.push_back(static_cast<int>(memberOrder.size()));
  }
  std::vector<int> newMember(M.size());
  for (size_t k = 0; k < memberOrder.size(); ++k) newMember[memberOrder[k]] = static_cast<int>(k);

  s.measured.clear();  // per block of bodies and contacts: another numbering, other blocks
  permute(B.pos, order); permute(B.vel, order); permute(B.angVel, order);
  permute(s.contacts.evaluation.pos, order);  // the branch vectors follow their bodies (Contacts::branch)
  permute(B.force, order); permute(B.torque, order); permute(B.mass, order);
  permute(B.inertia, order); permute(B.volume, order); permute(B.orientation, order);
  B.memberBegin = begin;
  permute(M.offset, memberOrder); permute(M.radius, memberOrder); permute(M.pos, memberOrder);
  permute(M.body, memberOrder);
  for (int& b : M.body) b = newBody[b];

  Contacts& C = s.contacts;
  const int nc = C.size();
  for (int c = 0; c < nc; ++c) {
    C.m1[c] = newMember[C.m1[c]]; C.m2[c] = newMember[C.m2[c]];
    C.b1[c] = newBody[C.b1[c]]; C.b2[c] = newBody[C.b2[c]];
    if (C.m1[c] > C.m2[c]) {  // the pair seen from its other side
      std::swap(C.m1[c], C.m2[c]);
      std::swap(C.b1[c], C.b2[c]);
      C.shift[c] = -C.shift[c];
      C.normal[c] = -C.normal[c];
      C.shearForce[c] = -C.shearForce[c];
      C.rollingMoment[c] = -C.rollingMoment[c];  // the moment on side 2; side 1 bears its opposite
    }
  }
  std::vector<int> pairs(nc);
  std::iota(pairs.begin(), pairs.end(), 0);
  std::sort(pairs.begin(), pairs.end(), [&](int a, int b) {
    return std::tie(C.m1[a], C.m2[a], C.shift[a][0], C.shift[a][1], C.shift[a][2]) <
           std::tie(C.m1[b], C.m2[b], C.shift[b][0], C.shift[b][1], C.shift[b][2]);
  });
  permute(C.m1, pairs); permute(C.m2, pairs); permute(C.b1, pairs); permute(C.b2, pairs);
  permute(C.shift, pairs); permute(C.rbar, pairs); permute(C.normal, pairs);
  permute(C.overlap, pairs); permute(C.normalForce, pairs); permute(C.shearForce, pairs);
  permute(C.rollingMoment, pairs);
  C.buildIncidence(nb);
  s.detectionInvalid = true;  // the detection's reference positions are in the old order
}

}  // namespace trueaniso
