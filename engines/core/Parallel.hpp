#pragma once
// When a loop is worth an OpenMP team. Entering a parallel region costs a few microseconds when
// the other core is idle, and a scheduler time slice (milliseconds) when it is busy with another
// process: a statics test took 1.2 s on one thread and 25.7 s on two while a second test program
// ran. A step of a small scene has several such regions and only microseconds of work in each, so
// loops shorter than kParallelMinimum items run on the calling thread (`#pragma omp ... if(...)`).
// Measured with another process on the second core: 300 spheres on two threads took 8-13 ms a
// step, on one 0.22 ms (docs/benchmarks.md). The value is where a loop holds about 50-100 us of
// work (10-25 ns an item), well above the few microseconds a team costs on idle cores.
namespace trueaniso {

constexpr int kParallelMinimum = 4096;

// Loops over contacts (about three per body touching, as many again within the skin) and over
// bodies use the same measure: the number of items the loop walks.
inline bool worthThreads(long items) { return items >= kParallelMinimum; }

}  // namespace trueaniso
