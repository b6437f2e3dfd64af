#include "client/refine_runner.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/common/error.h"
#include "proto/job_spec_json.h"

namespace satmesh::cli {

JobOutputs RunJobFile(const std::string& job_path, const std::string& out_dir,
                      const std::vector<std::string>& overrides) {
  std::ifstream in(job_path);
  SATMESH_CHECK(in.good(), ErrorCode::kNotFound, "job file '" + job_path + "' cannot be opened");
  nlohmann::json job;
  try {
    job = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    ThrowError(ErrorCode::kInvalidArgument, "job file '" + job_path + "': invalid JSON: " + e.what());
  }
  for (const auto& o : overrides) proto::ApplyOptionOverride(&job, o);
  const JobSpec spec =
      proto::JobSpecFromJson(job, std::filesystem::path(job_path).parent_path().string());

  Progress progress;
  progress.on_progress = [](double fraction, const std::string& stage) {
    std::fprintf(stderr, "\r[%3d%%] %-24s", int(100 * fraction), stage.c_str());
    if (fraction >= 1.0) std::fprintf(stderr, "\n");
  };
  JobOutputs outputs = RunJob(spec, out_dir, progress);
  proto::WriteJobJson(outputs, out_dir);
  spdlog::info("wrote {}, {}, {}/tileset.json, {}/metrics.json, {}/tiles/", outputs.mesh_path,
               outputs.dsm_path, out_dir, out_dir, out_dir);
  return outputs;
}

}  // namespace satmesh::cli
