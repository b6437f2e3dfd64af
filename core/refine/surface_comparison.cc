#include "core/refine/surface_comparison.h"

#include <cmath>

#include "core/common/error.h"
#include "core/refine/refine_level.h"
#include "core/refine/view_setup.h"

namespace satmesh {

std::vector<std::vector<PairComparison>> CommonWindowZncc(
    const RefineInput& input, const std::vector<TriangleMesh>& surfaces,
    const std::vector<std::pair<int, int>>& pairs, int level, const RefineOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "refine options: " + problem);
  SATMESH_CHECK(!surfaces.empty() && !pairs.empty(), ErrorCode::kInvalidArgument,
                "CommonWindowZncc: no surface or no pair");
  const std::vector<PreparedView> views = PrepareViews(input, level);
  const double gsd = views[pairs.front().first].gsd_m * std::ldexp(1.0, level);
  // windows[s][d]: surface s's window ZNCCs of direction d (2k, 2k + 1: pair k).
  std::vector<std::vector<std::vector<float>>> windows;
  for (const TriangleMesh& mesh : surfaces)
    windows.push_back(LevelWindowZncc(input, views, pairs, options, gsd, level, mesh));

  std::vector<std::vector<PairComparison>> out(surfaces.size(),
                                               std::vector<PairComparison>(pairs.size()));
  std::vector<double> sum(surfaces.size()), own_sum(surfaces.size());
  std::vector<long> own_count(surfaces.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    std::fill(sum.begin(), sum.end(), 0.0);
    std::fill(own_sum.begin(), own_sum.end(), 0.0);
    std::fill(own_count.begin(), own_count.end(), 0);
    long count = 0;
    for (size_t d : {2 * k, 2 * k + 1}) {
      const size_t n = windows[0][d].size();
      for (size_t p = 0; p < n; ++p) {
        bool everywhere = true;
        for (size_t s = 0; s < surfaces.size(); ++s) {
          const float z = windows[s][d][p];
          if (std::isnan(z)) {
            everywhere = false;
            continue;
          }
          own_sum[s] += z;
          ++own_count[s];
        }
        if (!everywhere) continue;
        for (size_t s = 0; s < surfaces.size(); ++s) sum[s] += windows[s][d][p];
        ++count;
      }
    }
    for (size_t s = 0; s < surfaces.size(); ++s)
      out[s][k] = {count > 0 ? sum[s] / double(count) : 0.0, count,
                   own_count[s] > 0 ? own_sum[s] / double(own_count[s]) : 0.0, own_count[s]};
  }
  return out;
}

}  // namespace satmesh
