#include "statics/Rattlers.hpp"

namespace trueaniso {

std::vector<char> findRattlers(const Scene& held) {
  const Contacts& C = held.contacts;
  const int nb = held.bodies.size();
  require(C.incBegin.size() == static_cast<size_t>(nb) + 1, "the held state has no incidence lists");
  std::vector<int> count(nb, 0);
  for (int c = 0; c < C.size(); ++c)
    if (C.normalForce[c] > 0) { ++count[C.b1[c]]; ++count[C.b2[c]]; }
  std::vector<char> rattler(nb, 0);
  std::vector<int> stack;
  for (int b = 0; b < nb; ++b)
    if (count[b] < 2) { rattler[b] = 1; stack.push_back(b); }
  while (!stack.empty()) {
    const int b = stack.back();
    stack.pop_back();
    for (int q = C.incBegin[b]; q < C.incBegin[b + 1]; ++q) {
      const int e = C.incidence[q];
      const int c = e >= 0 ? e : ~e;
      if (C.normalForce[c] <= 0) continue;
      const int other = C.b1[c] == b ? C.b2[c] : C.b1[c];
      if (rattler[other]) continue;
      if (--count[other] < 2) { rattler[other] = 1; stack.push_back(other); }
    }
  }
  return rattler;
}

}  // namespace trueaniso
