#pragma once
// When a loop is worth an OpenMP team. Entering a parallel region costs a few microseconds when
// the other core is idle, and a scheduler time slice (milliseconds) when it is busy with another
// process: a statics test took 1.2 s on one thread and 25.7 s on two while a second test program
// ran. A step of a small scene has several such regions and only microseconds of work in each, so
// loops shorter than parallelMinimum() items run on the calling thread (`#pragma omp ... if(...)`).
// Measured with another process on the second core: 300 spheres on two threads took 8-13 ms a
// step, on one 0.22 ms (docs/benchmarks.md, "Stepper changes"). The default is where a loop holds
// about 50-100 us of work (10-25 ns an item), well above the few microseconds a team costs on idle
// cores; a machine with other costs can set its own (engines.set_parallel_minimum).
#include <atomic>

namespace trueaniso {

constexpr int kDefaultParallelMinimum = 4096;

inline std::atomic<int>& parallelMinimumSetting() {
  static std::atomic<int> items{kDefaultParallelMinimum};
  return items;
}
inline int parallelMinimum() { return parallelMinimumSetting().load(std::memory_order_relaxed); }
inline void setParallelMinimum(int items) { parallelMinimumSetting().store(items < 0 ? 0 : items); }

// Loops over contacts (about three per body touching, as many again within the skin) and over
// bodies use the same measure: the number of items the loop walks.
inline bool worthThreads(long items) { return items >= parallelMinimum(); }

// The loops a step runs beside its contact loop over the bodies or members (the integrator, the
// detection's displacement check and its search for pairs), whose results do not depend on how
// the items are shared (each item on its own, a maximum, lists joined in order): on the team when
// the step's contact loop is, that is when the scene has parallelMinimum() contacts, or when they
// are that many themselves. A body's integration costs about what a contact's force does (4000
// spheres: 100 us a step on one thread, a tenth of the step), far above the few microseconds a
// team costs, and a step whose contact loop runs on the team already waits for the second core.
inline bool worthThreadsBeside(long items, long contacts) { return worthThreads(items > contacts ? items : contacts); }

}  // namespace trueaniso
