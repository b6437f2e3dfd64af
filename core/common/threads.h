#pragma once
// How many threads a tile worker's parallel loops use when several workers refine tiles
// at once (in-process job runner, server scheduler).

#include <functional>

namespace satmesh {

// Shares the machine's processors among `workers` concurrent workers: the OpenMP loops
// that the calling thread starts from now on use max(1, processors / workers) threads
// (a per-thread setting; other threads are unaffected). Returns that number. Without it
// each of N workers starts a team on every processor: N times as many busy threads as
// processors, spinning at each other's barriers (docs/benchmarks-history.md, session 8).
int ShareProcessorsAmongWorkers(int workers);

// Runs `side` on a thread of its own (its OpenMP loops with the calling thread's number of
// threads) while the calling thread runs `main`; returns when both have returned. An
// exception of either is rethrown here, `main`'s first.
void RunAlongside(const std::function<void()>& side, const std::function<void()>& main);

}  // namespace satmesh
