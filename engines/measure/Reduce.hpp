#pragma once
// Sums over contacts or bodies in fixed blocks, combined in block order, so that a measure is the
// same to the last bit whatever the number of threads.
#include <algorithm>
#include <vector>

#include "core/Parallel.hpp"
#include "core/Types.hpp"

namespace trueaniso {

template <class T, class F>
T blockSum(int n, const T& zero, F&& term) {
  constexpr int kBlock = 512;
  const int blocks = (n + kBlock - 1) / kBlock;
  std::vector<T> partial(blocks, zero);
#pragma omp parallel for schedule(static) if (worthThreads(n))
  for (int k = 0; k < blocks; ++k) {
    T acc = zero;
    const int end = std::min(n, (k + 1) * kBlock);
    for (int i = k * kBlock; i < end; ++i) term(i, acc);
    partial[k] = acc;
  }
  T total = zero;
  for (const T& p : partial) total += p;
  return total;
}

}  // namespace trueaniso
