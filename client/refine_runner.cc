#include "client/refine_runner.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "core/common/error.h"
#include "proto/job_pictures.h"
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

// DIR/viewer.html (the page satmesh-server serves at /jobs/{id}/viewer) and DIR/Cesium, a
// link to the CesiumJS the build (or the image) carries: any static file server started
// in DIR shows the result. SATMESH_VIEWER_DIR overrides where they are taken from.
void WriteViewer(const std::string& out_dir) {
  namespace fs = std::filesystem;
  const char* env = std::getenv("SATMESH_VIEWER_DIR");
  const fs::path from = env && *env ? fs::path(env) : fs::path(SATMESH_VIEWER_DIR);
  std::error_code ec;
  if (!fs::exists(from / "viewer.html", ec) || !fs::exists(from / "Cesium" / "Cesium.js", ec)) {
    spdlog::warn("no viewer written: '{}' has no viewer.html and Cesium/ (set SATMESH_VIEWER_DIR)", from.string());
    return;
  }
  fs::copy_file(from / "viewer.html", fs::path(out_dir) / "viewer.html", fs::copy_options::overwrite_existing);
  const fs::path link = fs::path(out_dir) / "Cesium";
  if (fs::is_symlink(link, ec) || !fs::exists(link, ec)) {
    fs::remove(link, ec);
    fs::create_directory_symlink(fs::canonical(from / "Cesium"), link);
  }
  spdlog::info("viewer: {}/viewer.html (serve {} over HTTP, e.g. python3 -m http.server -d {})", out_dir, out_dir, out_dir);
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
  proto::WriteJobPictures(proto::JobMetricsToJson(outputs), out_dir);
  WriteViewer(out_dir);
  spdlog::info("wrote {}, {}, {}/tileset.json, {}/metrics.json, {}/tiles/, {}/preview.png (hillshade), "
               "{}/convergence.png (ZNCC per iteration)", outputs.mesh_path, outputs.dsm_path, out_dir,
               out_dir, out_dir, out_dir, out_dir);
  return outputs;
}

}  // namespace satmesh::cli
