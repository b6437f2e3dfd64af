#include "client/eval_pictures.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/mesh/mesh_io.h"
#include "core/pictures/pictures.h"
#include "proto/job_pictures.h"

namespace satmesh::cli {
namespace fs = std::filesystem;

namespace {

std::string Title(const char* what, const DsmMetrics& m) {
  char text[128];
  std::snprintf(text, sizeof(text), "%s: RMSE %.2f m, NMAD %.2f m", what, m.rmse_m, m.nmad_m);
  return text;
}

}  // namespace

std::vector<std::string> WriteEvalPictures(const std::string& scene_dir, const std::string& result_path,
                                           const SceneEvaluation& evaluation, const std::string& out_dir,
                                           double range_m) {
  fs::create_directories(out_dir);
  std::vector<std::string> written;
  const ScenePaths paths = SceneLayout(scene_dir);
  const Dsm truth = ReadDsm(paths.truth_dsm);
  const Dsm initial = ReadDsm(paths.initial_dsm);
  const std::string mesh_path = fs::is_directory(result_path) ? (fs::path(result_path) / "mesh.ply").string() : result_path;
  const Dsm refined = DsmFromMesh(ReadMesh(mesh_path), truth);
  const std::string errors = (fs::path(out_dir) / "height_error.png").string();
  WriteHeightErrorMapsPng(errors,
                          {{Title("initial DSM", evaluation.initial.dsm.all_raw), &initial},
                           {Title("refined", evaluation.result.dsm.all_raw), &refined}},
                          truth, range_m);
  written.push_back(errors);
  const fs::path metrics_path = fs::path(result_path) / "metrics.json";
  if (fs::is_directory(result_path) && fs::exists(metrics_path)) {
    std::ifstream in(metrics_path);
    const auto metrics = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    const auto series = metrics.is_discarded() ? std::vector<PlotSeries>{} : proto::ConvergenceSeries(metrics);
    if (!series.empty()) {
      const std::string zncc = (fs::path(out_dir) / "zncc.png").string();
      WriteLinePlotPng(zncc, series, "mean ZNCC per iteration, per level", "iteration", "mean ZNCC");
      written.push_back(zncc);
    }
  }
  return written;
}

}  // namespace satmesh::cli
