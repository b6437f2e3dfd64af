#pragma once
// One level of the refinement (paper 3.2-3.4): its iterations of hit maps, pair gradients,
// thin plate and update, and the mean ZNCC of a surface at a level. Used by Refine
// (refine.cc), which runs the levels coarse to fine.
#include <utility>
#include <vector>

#include "core/common/progress.h"
#include "core/mesh/mesh.h"
#include "core/refine/refine.h"
#include "core/refine/view_setup.h"

namespace satmesh {

struct LevelContext {
  const RefineInput& input;
  const RefineOptions& options;
  const Progress& progress;
  const std::vector<PreparedView>& sources;
  std::vector<std::pair<int, int>>& pairs;
  double mean_pair_information;  // MeanRelativePairInformation of the selected pairs
  double gsd_m;
};

// pairs_per_iteration: `pairs` fall into PairGroups groups (one when it is 0) of at least
// that many pairs and at least half as many as the views they join (so that a group can
// see every view), spread over the views (PairGroupIndices). A level's middle iterations
// take the groups in turn (RefineLevel); the initial surface is measured on group 0 alone
// (InitialCheckPairs).
int PairGroups(const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options);
std::vector<std::pair<int, int>> PairGroup(const std::vector<std::pair<int, int>>& pairs,
                                           int groups, int group);

// The pairs a level below the coarsest compares the initial surface and the previous
// level's result on (refine.cc, CoarseToFine): group 0, a sample spread over the selection
// and its views. Measuring the initial surface, a grid mesh
// of about twice the level's faces, on every pair of a 26-view set cost 9% of the large
// job; a margin of 0.08 in ZNCC there, ties within 0.001 on the Pléiades triplet (3
// pairs: one group).
std::vector<std::pair<int, int>> InitialCheckPairs(const std::vector<std::pair<int, int>>& pairs,
                                                   const RefineOptions& options);

// The iterations of one level. Returns false, before changing the mesh, if the mean ZNCC
// of the level's first iteration over InitialCheckPairs (stats_out->check_zncc) is below
// `abandon_below` (NaN: never).
bool RefineLevel(const LevelContext& ctx, int level, double abandon_below, TriangleMesh* mesh,
                 LevelStats* stats_out);

// Mean ZNCC of `mesh` over `pairs` at `level`, without changing anything; hit maps
// rasterized or cast with Embree; moving shadows left out as RefineLevel leaves them out
// (sunlit_pairs), so the two compare.
double LevelZncc(const RefineInput& input, const std::vector<PreparedView>& sources,
                 const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                 double level_gsd_m, int level, const TriangleMesh& mesh, bool rasterize);

// LevelZncc's pass (Embree), keeping each window's ZNCC: per direction d of the pairs
// (d = 2k: pair k as (i, j), view i's pixels; d = 2k + 1: as (j, i)), view i's level image
// of window ZNCCs, NaN where the window is not counted.
std::vector<std::vector<float>> LevelWindowZncc(const RefineInput& input,
                                                const std::vector<PreparedView>& sources,
                                                const std::vector<std::pair<int, int>>& pairs,
                                                const RefineOptions& options, double level_gsd_m,
                                                int level, const TriangleMesh& mesh);

// The images' height sigma of each vertex of `mesh` at `level` (metres; +inf where no
// pair sees it): one photometric pass over both directions of every pair, gathering the
// Fisher information (HeightSigmaFromInformation), without changing anything.
std::vector<float> LevelHeightSigma(const RefineInput& input,
                                    const std::vector<PreparedView>& sources,
                                    const std::vector<std::pair<int, int>>& pairs,
                                    const RefineOptions& options, double level_gsd_m, int level,
                                    const TriangleMesh& mesh);

// Both from one rasterized pass: LevelHeightSigma, and the mean ZNCC as LevelZncc measures
// it (moving shadows left out as the level's iterations leave them out, sunlit_pairs).
struct LevelMeasure {
  std::vector<float> height_sigma;
  double mean_zncc = 0;
};
LevelMeasure MeasureLevel(const RefineInput& input, const std::vector<PreparedView>& sources,
                          const std::vector<std::pair<int, int>>& pairs,
                          const RefineOptions& options, double level_gsd_m, int level,
                          const TriangleMesh& mesh);

}  // namespace satmesh
