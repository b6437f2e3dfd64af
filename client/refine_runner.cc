#include "client/refine_runner.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "core/common/error.h"
#include "proto/job_spec_json.h"

namespace satmesh::cli {

JobSpec ReadJobWithOverrides(const std::string& job_path, const std::vector<std::string>& overrides) {
  std::ifstream in(job_path);
  SATMESH_CHECK(in.good(), ErrorCode::kNotFound, "job file '" + job_path + "' cannot be opened");
  nlohmann::json job;
  try {
    job = nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    ThrowError(ErrorCode::kInvalidArgument, "job file '" + job_path + "': invalid JSON: " + e.what());
  }
  for (const auto& o : overrides) proto::ApplyOptionOverride(&job, o);
  return proto::JobSpecFromJson(job, std::filesystem::path(job_path).parent_path().string());
}

JobOutputs RunJobFile(const std::string& job_path, const std::string& out_dir,
                      const std::vector<std::string>& overrides) {
  const JobSpec spec = ReadJobWithOverrides(job_path, overrides);
  // A live line on a terminal; in logs (CI, pipes) one line per 10%.
  const bool tty = ::isatty(::fileno(stderr));
  Progress progress;
  progress.on_progress = [tty, last = -1](double fraction, const std::string& stage) mutable {
    const int percent = int(100 * fraction);
    if (tty) {
      std::fprintf(stderr, "\r[%3d%%] %-24s", percent, stage.c_str());
      if (fraction >= 1.0) std::fprintf(stderr, "\n");
    } else if (percent / 10 != last / 10) {
      std::fprintf(stderr, "[%3d%%] %s\n", percent, stage.c_str());
    }
    last = percent;
  };
  JobOutputs outputs = RunJob(spec, out_dir, progress);
  proto::WriteJobJson(outputs, out_dir);
  spdlog::info("wrote {}, {}, {}/tileset.json, {}/metrics.json, {}/tiles/", outputs.mesh_path,
               outputs.dsm_path, out_dir, out_dir, out_dir);
  return outputs;
}

}  // namespace satmesh::cli
