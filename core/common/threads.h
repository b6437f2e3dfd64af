#pragma once
// How many threads a tile worker's parallel loops use when several workers refine tiles
// at once (in-process job runner, server scheduler).

namespace satmesh {

// Shares the machine's processors among `workers` concurrent workers: the OpenMP loops
// that the calling thread starts from now on use max(1, processors / workers) threads
// (a per-thread setting; other threads are unaffected). Returns that number. Without it
// each of N workers starts a team on every processor: N times as many busy threads as
// processors, spinning at each other's barriers (docs/benchmarks-history.md, session 8).
int ShareProcessorsAmongWorkers(int workers);

}  // namespace satmesh
