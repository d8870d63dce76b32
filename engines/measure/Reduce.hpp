#pragma once
// Sums over contacts or bodies in fixed blocks, combined in block order, so that a measure is the
// same to the last bit whatever the number of threads.
#include <algorithm>
#include <vector>

#include "core/Parallel.hpp"
#include "core/Types.hpp"

namespace trueaniso {

// The block of every such sum. The force loop gives each thread whole blocks of pairs, so that
// the measures it accumulates while it computes the forces are these sums to the bit
// (measure/CellSums.hpp).
constexpr int kSumBlock = 512;

// `block(begin, end, acc)` adds the items [begin, end) of one block to acc (which starts at `zero`);
// the blocks' results are added in block order.
template <class T, class F>
T blockReduce(int n, const T& zero, F&& block) {
  const int blocks = (n + kSumBlock - 1) / kSumBlock;
  std::vector<T> partial(blocks, zero);
#pragma omp parallel for schedule(static) if (worthThreads(n))
  for (int k = 0; k < blocks; ++k) {
    T acc = zero;
    block(k * kSumBlock, std::min(n, (k + 1) * kSumBlock), acc);
    partial[k] = acc;
  }
  T total = zero;
  for (const T& p : partial) total += p;
  return total;
}

// `term(i, acc)` adds item i to acc, item after item in each block.
template <class T, class F>
T blockSum(int n, const T& zero, F&& term) {
  return blockReduce<T>(n, zero, [&](int begin, int end, T& acc) {
    for (int i = begin; i < end; ++i) term(i, acc);
  });
}

}  // namespace trueaniso
