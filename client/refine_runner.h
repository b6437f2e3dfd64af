#pragma once
// Shared by `satmesh refine` and `satmesh demo`: job file (+ overrides) -> RunJob ->
// tileset.json + metrics.json, with a progress line on the terminal.
#include <string>
#include <vector>

#include "core/tiling/job.h"

namespace satmesh::cli {

// Reads the job, applies --set overrides, runs it into out_dir (mesh.ply, dsm.tif, tiles/)
// and writes out_dir/tileset.json and out_dir/metrics.json.
JobOutputs RunJobFile(const std::string& job_path, const std::string& out_dir,
                      const std::vector<std::string>& overrides);

}  // namespace satmesh::cli
