#pragma once
// How many threads a tile worker's parallel loops use when several workers refine tiles
// at once (in-process job runner, server scheduler).

#include <cstddef>

namespace satmesh {

// Shares the machine's processors among `workers` concurrent workers: the OpenMP loops
// that the calling thread starts from now on use max(1, processors / workers) threads
// (a per-thread setting; other threads are unaffected). Returns that number. Without it
// each of N workers starts a team on every processor: N times as many busy threads as
// processors, spinning at each other's barriers (docs/benchmarks-history.md, session 8).
int ShareProcessorsAmongWorkers(int workers);

// Whether `items` units of like work (views to rasterize, pair-directions to warp) run one
// per thread of the calling thread's team, or one after the other with the team inside
// each (their own parallel loops). One per thread leaves threads idle where there are
// fewer units than threads (a stereo pair's one direction a pass: one of two cores), and a
// remainder leaves the last units to some threads while the others wait (3 views on 2
// threads: a third of the time); from 4 units a thread on, the remainder is small.
bool OnePerThread(size_t items);

}  // namespace satmesh
