#include "client/eval_pictures.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/eval/mesh_metrics.h"
#include "core/eval/surface_distance.h"
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

std::vector<std::string> WriteEvalPictures(const std::string& scene_dir,
                                           const std::string& result_path,
                                           const SceneEvaluation& evaluation,
                                           const std::string& out_dir, double range_m) {
  fs::create_directories(out_dir);
  std::vector<std::string> written;
  const ScenePaths paths = SceneLayout(scene_dir);
  const Dsm truth = ReadDsm(paths.truth_dsm);
  const Dsm initial = ReadDsm(paths.initial_dsm);
  const std::string mesh_path =
      fs::is_directory(result_path) ? (fs::path(result_path) / "mesh.ply").string() : result_path;
  const Dsm refined = DsmFromMesh(ReadMesh(mesh_path), truth);
  const std::string errors = (fs::path(out_dir) / "height_error.png").string();
  WriteHeightErrorMapsPng(errors,
                          {{Title("initial DSM", evaluation.initial.dsm.all_raw), &initial},
                           {Title("refined", evaluation.result.dsm.all_raw), &refined}},
                          truth, range_m);
  written.push_back(errors);
  // Facades: the truth's facade samples, coloured by their distance to each surface.
  if (fs::exists(paths.truth_mesh)) {
    const TriangleMesh truth_mesh = ReadMesh(paths.truth_mesh);
    const SurfaceSamples samples = SampleSurface(truth_mesh);
    const auto& gt = truth.geo_transform;
    const std::array<double, 4> extent = {gt[0], gt[3] + truth.height * gt[5],
                                          gt[0] + truth.width * gt[1], gt[3]};
    std::vector<Eigen::Vector3d> facade;
    for (size_t i = 0; i < samples.points.size(); ++i) {
      const Eigen::Vector3d& p = samples.points[i];
      if (IsFacadeNormal(samples.normals[i], 0.3) && p.x() >= extent[0] && p.x() <= extent[2] &&
          p.y() >= extent[1] && p.y() <= extent[3])
        facade.push_back(p);
    }
    std::vector<Eigen::Vector2d> xy;
    for (const auto& p : facade) xy.emplace_back(p.x(), p.y());
    const double max_m = 2.0;
    const auto panel = [&](const char* what, const TriangleMesh& mesh) {
      PointPanel p{"", xy, SurfaceDistance(mesh).Distances(facade, max_m)};
      size_t near = 0;
      for (float d : p.values) near += d < 1.0f;
      char title[128];
      std::snprintf(title, sizeof(title), "%s: %.0f%% of facade samples within 1 m", what,
                    100.0 * double(near) / double(std::max<size_t>(1, p.values.size())));
      p.title = title;
      return p;
    };
    const std::string facades = (fs::path(out_dir) / "facade_distance.png").string();
    WritePointMapsPng(
        facades,
        {panel("initial DSM", MeshFromDsm(initial)), panel("refined", ReadMesh(mesh_path))}, extent,
        max_m, "distance of the true facades to the surface (m), mean seen from above");
    written.push_back(facades);
  }
  const fs::path metrics_path = fs::path(result_path) / "metrics.json";
  if (fs::is_directory(result_path) && fs::exists(metrics_path)) {
    std::ifstream in(metrics_path);
    const auto metrics = nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
    const auto series =
        metrics.is_discarded() ? std::vector<PlotSeries>{} : proto::ConvergenceSeries(metrics);
    if (!series.empty()) {
      const std::string zncc = (fs::path(out_dir) / "zncc.png").string();
      WriteLinePlotPng(zncc, series, "mean ZNCC per iteration, per level", "iteration",
                       "mean ZNCC");
      written.push_back(zncc);
    }
  }
  return written;
}

}  // namespace satmesh::cli
