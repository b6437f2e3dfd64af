#pragma once
// The mesh each level of the refinement starts from (Refine, refine.cc, step 4): the
// initial surface remeshed or gridded at the level's triangle edge, at full resolution
// refined where the images cannot form the initial surface's detail themselves.
#include <optional>
#include <utility>
#include <vector>

#include "core/common/progress.h"
#include "core/mesh/mesh.h"
#include "core/refine/refine.h"
#include "core/refine/view_setup.h"

namespace satmesh {

// Triangle edge of `level`, metres: coarse_edge_px level pixels.
double LevelEdge(const RefineOptions& options, double gsd_m, int level);

// `mesh` remeshed isotropically to the triangle edge of `level` (see level_start.cc);
// grid_cell_m > 0: GridKeepingTargetEdge; edge_px > 0: that edge instead of coarse_edge_px.
TriangleMesh RemeshForLevel(const RefineInput& input, TriangleMesh mesh,
                            const RefineOptions& options, double gsd_m, int level,
                            const Progress& progress, double grid_cell_m = 0,
                            double edge_px = 0);

// The initial surface meshed for `level` (before remeshing): what a level below the
// coarsest measures and, if it wins, restarts from.
TriangleMesh InitialSurfaceAt(const RefineInput& input, const RefineOptions& options,
                              double gsd_m, int level);

// The mesh `level` starts from (see level_start.cc). median_sigma_m: at level 0, the median
// vertex's height sigma from the pairs (NaN where the test did not run). adaptive_taken:
// whether it is the adaptive start (AdaptiveStart: flat_edge_px, subdivided), not the
// level's uniform triangles.
TriangleMesh LevelStartMesh(const RefineInput& input, const RefineOptions& options,
                            const std::vector<PreparedView>& views,
                            const std::vector<std::pair<int, int>>& pairs, double gsd_m,
                            const Progress& progress, int level,
                            double* median_sigma_m = nullptr, bool* adaptive_taken = nullptr);

// Step 4a, RefineOptions::grid_start -1 resolved: 1 for the DSM's own grid, 0 for the
// remesh (see level_start.cc). `grid`, `grid_zncc`: the grid and its mean ZNCC where taken.
int ChooseCoarseStart(const RefineInput& input, const RefineOptions& options,
                      const std::vector<PreparedView>& views,
                      const std::vector<std::pair<int, int>>& pairs, double gsd_m,
                      std::optional<TriangleMesh>* grid, double* grid_zncc);

// RefineOptions::flat_edge_px resolved, after levels and grid_start are: -1 gives
// 2 x coarse_edge_px to a DSM start remeshed at full resolution (no coarser level, grid_start
// 0) with more than one pair, 1.85 x with one pair, else coarse_edge_px (see level_start.cc,
// AdaptiveStart). Where the images resolve the surface LevelStartMesh falls back to
// coarse_edge_px.
double ResolveFlatEdge(const RefineOptions& options, bool initial_is_mesh, size_t num_pairs);

// Per face of `mesh`, 1 where each of its vertices' `sigma` (per vertex, metres; +inf or NaN:
// unconstrained) is at most limit_m: the faces one pair's adaptive start halves at once.
std::vector<char> FacesWithinSigma(const TriangleMesh& mesh, const std::vector<float>& sigma,
                                   double limit_m);

// The finest triangle edge (pixels) an adaptive start is subdivided to where the initial
// surface departs from it: half of coarse_edge_px; with one pair, the initial surface's
// own cells (initial_cell_px: its mesh's grid cell in pixels, 0 where unknown) within
// [half of coarse_edge_px, coarse_edge_px].
double FinestDetailPx(double coarse_edge_px, size_t num_pairs, double initial_cell_px);

// The number of times a start of flat_edge_px pixels is subdivided where the initial
// surface departs from it: until its finest triangles are at most finest_px
// (FinestDetailPx), at least once. 4 to 1 pixel: 2 (4 -> 2 -> 1); 2 to 1: 1; 3.7 to 2:
// 1 (3.7 -> 1.85).
int DetailRounds(double flat_edge_px, double finest_px);

}  // namespace satmesh
