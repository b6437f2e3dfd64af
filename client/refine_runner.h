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

// Writes out_dir/viewer.html and the link out_dir/Cesium (from SATMESH_VIEWER_DIR, else the
// build's viewer folder) so that a static file server in out_dir shows out_dir/tileset.json;
// warns and writes nothing when the viewer folder is missing.
void WriteViewer(const std::string& out_dir);

}  // namespace satmesh::cli
