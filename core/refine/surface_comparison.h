#pragma once
// Comparing surfaces by their photo-consistency over one support (held-out-view checks).
// A surface's mean ZNCC (MeasureMeanZncc) averages the windows that surface makes valid,
// and two surfaces make different ones: their extents, what each occludes, the faces each
// shows at grazing angles. On a synthetic tri-stereo scene with the Pléiades triplet's
// angles (6.6 / 6.9 / 13.5 deg), the true mesh scores 0.007-0.010 below the initial DSM on
// the narrow pairs by its own windows, and 0.002-0.005 above it over the windows both
// count (docs/benchmarks-history.md, session 29).
#include <utility>
#include <vector>

#include "core/refine/refine.h"

namespace satmesh {

struct PairComparison {
  double mean_zncc = 0;  // over the windows every surface counts, both directions
  long windows = 0;      // how many (the same for every surface)
  double own_mean_zncc = 0;  // over the windows this surface counts (MeasureMeanZncc's)
  long own_windows = 0;
};

// result[s][k]: surface s (in input.frame) over pair k at pyramid level `level`, through the
// pass MeasureMeanZncc runs (Embree hit maps, moving shadows left out as the refinement
// leaves them out), on the windows of pair k's two directions that every surface counts,
// and on those it counts itself (one pass a surface gives both).
std::vector<std::vector<PairComparison>> CommonWindowZncc(
    const RefineInput& input, const std::vector<TriangleMesh>& surfaces,
    const std::vector<std::pair<int, int>>& pairs, int level, const RefineOptions& options = {});

}  // namespace satmesh
