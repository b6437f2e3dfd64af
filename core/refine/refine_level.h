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

// The iterations of one level. Returns false, before changing the mesh, if the mean ZNCC
// of the level's first iteration is below `abandon_below` (NaN: never).
bool RefineLevel(const LevelContext& ctx, int level, double abandon_below, TriangleMesh* mesh,
                 LevelStats* stats_out);

// Mean ZNCC of `mesh` over `pairs` at `level`, without changing anything; hit maps
// rasterized or cast with Embree; moving shadows left out as RefineLevel leaves them out
// (sunlit_pairs), so the two compare.
double LevelZncc(const RefineInput& input, const std::vector<PreparedView>& sources,
                 const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                 double level_gsd_m, int level, const TriangleMesh& mesh, bool rasterize);

// The images' height sigma of each vertex of `mesh` at `level` (metres; +inf where no
// pair sees it): one photometric pass over both directions of every pair, gathering the
// Fisher information (HeightSigmaFromInformation), without changing anything.
std::vector<float> LevelHeightSigma(const RefineInput& input,
                                    const std::vector<PreparedView>& sources,
                                    const std::vector<std::pair<int, int>>& pairs,
                                    const RefineOptions& options, double level_gsd_m, int level,
                                    const TriangleMesh& mesh);

}  // namespace satmesh
