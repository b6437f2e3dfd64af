#pragma once
// Pictures of an evaluation on a synthetic scene (satmesh eval --pictures, satmesh demo).
#include <string>
#include <vector>

#include "core/eval/scene_eval.h"

namespace satmesh::cli {

// out_dir/height_error.png: the initial DSM and the result mesh (rasterised on the truth
// grid) minus the truth, side by side on one colour scale (+-range_m), each titled with its
// raw RMSE and NMAD over all cells; out_dir/facade_distance.png: the truth's facade
// samples seen from above, coloured by their distance to the initial and to the result
// surface (0-2 m, one scale); out_dir/zncc.png: the result's mean ZNCC per iteration
// and level, when result_path is a directory with metrics.json. Returns the paths written.
std::vector<std::string> WriteEvalPictures(const std::string& scene_dir,
                                           const std::string& result_path,
                                           const SceneEvaluation& evaluation,
                                           const std::string& out_dir, double range_m = 2.0);

}  // namespace satmesh::cli
