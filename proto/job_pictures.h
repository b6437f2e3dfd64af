#pragma once
// The pictures of a job's results, made from what its metrics.json says (shared by the
// CLI's refine and the server's assembly): DIR/preview.png, a hillshade of DIR/dsm.tif, and
// DIR/convergence.png, the mean ZNCC per iteration of every level (tiles' face-weighted mean).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/pictures/pictures.h"

namespace satmesh::proto {

// One series per level of metrics["levels"] ("level L, GSD g m"), coarse to fine.
std::vector<PlotSeries> ConvergenceSeries(const nlohmann::json& metrics);

// Writes out_dir/preview.png and out_dir/convergence.png (the latter only when a level has
// a ZNCC); returns the names written. Throws Error naming the file on failure.
std::vector<std::string> WriteJobPictures(const nlohmann::json& metrics,
                                          const std::string& out_dir);

}  // namespace satmesh::proto
