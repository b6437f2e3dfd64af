#pragma once
// Shared by `satmesh refine` and `satmesh demo`: job file (+ overrides) -> RunJob ->
// tileset.json + metrics.json, with a progress line on the terminal.
#include <string>
#include <vector>

#include "core/tiling/job.h"

namespace satmesh::cli {

// Reads a job file and applies --set overrides (hrefs relative to the job file). Throws
// Error naming the file or the field.
JobSpec ReadJobWithOverrides(const std::string& job_path, const std::vector<std::string>& overrides);

// Reads the job, applies --set overrides, runs it into out_dir (mesh.ply, dsm.tif, tiles/)
// and writes out_dir/tileset.json and out_dir/metrics.json.
JobOutputs RunJobFile(const std::string& job_path, const std::string& out_dir,
                      const std::vector<std::string>& overrides);

}  // namespace satmesh::cli
