#include "core/eval/scene_eval.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numeric>

#include "core/common/error.h"
#include "core/common/stats.h"
#include "core/dsm/dsm.h"
#include "core/eval/scene_views.h"
#include "core/eval/surface_distance.h"
#include "core/mesh/mesh_io.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

void RequireFile(const std::string& path, const std::string& what) {
  SATMESH_CHECK(fs::is_regular_file(path), ErrorCode::kNotFound,
                what + " not found: '" + path + "'");
}

std::string ResultMeshPath(const std::string& result_path) {
  if (fs::is_directory(result_path)) return (fs::path(result_path) / "mesh.ply").string();
  return result_path;
}

}  // namespace

std::vector<SigmaBin> ErrorBySigma(const TriangleMesh& result, const TriangleMesh& truth,
                                   double xmin, double xmax, double ymin, double ymax) {
  std::vector<SigmaBin> bins;
  if (result.height_sigma.size() != result.vertices.size() || truth.faces.empty()) return bins;
  std::vector<Eigen::Vector3d> points;
  std::vector<float> sigma;
  for (size_t i = 0; i < result.vertices.size(); ++i) {
    const Eigen::Vector3d p = result.AbsoluteVertex(i);
    if (p.x() < xmin || p.x() > xmax || p.y() < ymin || p.y() > ymax) continue;
    if (std::isnan(result.height_sigma[i])) continue;
    points.push_back(p);
    sigma.push_back(result.height_sigma[i]);
  }
  const std::vector<float> error = SurfaceDistance(truth).Distances(points, 10.0);
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return sigma[a] < sigma[b]; });
  size_t finite = 0;
  while (finite < order.size() && std::isfinite(sigma[order[finite]])) ++finite;
  auto add = [&](size_t begin, size_t end) {
    if (end <= begin) return;
    SigmaBin bin;
    bin.sigma_min_m = sigma[order[begin]];
    bin.sigma_max_m = sigma[order[end - 1]];
    bin.vertices = end - begin;
    std::vector<double> e;
    for (size_t k = begin; k < end; ++k) e.push_back(error[order[k]]);
    bin.median_error_m = Quantile(e, 0.5);
    bin.p90_error_m = Quantile(e, 0.9);
    bins.push_back(bin);
  };
  for (int d = 0; d < 10; ++d) add(finite * d / 10, finite * (d + 1) / 10);
  add(finite, order.size());  // no image saw them
  return bins;
}

std::string SceneEvalOptions::Check() const {
  if (auto m = dsm.Check(); !m.empty()) return "dsm: " + m;
  if (auto m = mesh3d.Check(); !m.empty()) return "mesh3d: " + m;
  return "";
}

ScenePaths SceneLayout(const std::string& scene_dir) {
  const fs::path d(scene_dir);
  return {(d / "truth" / "mesh.ply").string(), (d / "truth" / "dsm.tif").string(),
          (d / "truth" / "roof_mask.tif").string(), (d / "initial" / "dsm.tif").string(),
          (d / "images").string()};
}

SurfaceEvaluation EvaluateSurface(const Dsm& dsm, const TriangleMesh& mesh, const Dsm& truth_dsm,
                                  const std::vector<uint8_t>& mask, const TriangleMesh* truth_mesh,
                                  const SceneEvalOptions& options, const ViewDirectionsFn* views) {
  SurfaceEvaluation e;
  e.dsm = EvaluateDsm(dsm, truth_dsm, mask, options.dsm);
  if (options.evaluate_3d && truth_mesh)
    e.mesh3d = EvaluateMesh3d(mesh, *truth_mesh, options.mesh3d, views);
  return e;
}

SceneEvaluation EvaluateScene(const std::string& scene_dir, const std::string& result_path,
                              const SceneEvalOptions& options) {
  const std::string mesh_path = ResultMeshPath(result_path);
  RequireFile(mesh_path, "result mesh");
  return EvaluateScene(scene_dir, ReadMesh(mesh_path), options);
}

SceneEvaluation EvaluateScene(const std::string& scene_dir, const TriangleMesh& result,
                              const SceneEvalOptions& options_in) {
  const std::string msg = options_in.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, "SceneEvalOptions: " + msg);
  const ScenePaths paths = SceneLayout(scene_dir);
  RequireFile(paths.truth_dsm, "truth DSM");
  RequireFile(paths.roof_mask, "roof mask");
  RequireFile(paths.initial_dsm, "initial DSM");
  if (options_in.evaluate_3d) RequireFile(paths.truth_mesh, "truth mesh");

  const Dsm truth_dsm = ReadDsm(paths.truth_dsm);
  const std::vector<uint8_t> mask = MaskFromDsm(ReadDsm(paths.roof_mask));
  const Dsm initial_dsm = ReadDsm(paths.initial_dsm);
  TriangleMesh truth_mesh;
  if (options_in.evaluate_3d) truth_mesh = ReadMesh(paths.truth_mesh);

  SceneEvalOptions options = options_in;  // 3D samples only over the truth grid's extent
  const auto& gt = truth_dsm.geo_transform;
  const double x0 = gt[0], x1 = gt[0] + truth_dsm.width * gt[1];
  const double y0 = gt[3], y1 = gt[3] + truth_dsm.height * gt[5];
  options.mesh3d.crop_xmin = std::min(x0, x1);
  options.mesh3d.crop_xmax = std::max(x0, x1);
  options.mesh3d.crop_ymin = std::min(y0, y1);
  options.mesh3d.crop_ymax = std::max(y0, y1);

  SceneEvaluation s;
  s.grid_width = truth_dsm.width;
  s.grid_height = truth_dsm.height;
  s.gsd_m = std::abs(gt[1]);
  for (uint8_t m : mask) s.num_mask_cells += m;
  spdlog::info("eval: initial surface ({}x{} cells, {} roof cells)", s.grid_width, s.grid_height,
               s.num_mask_cells);
  ViewDirectionsFn views;
  if (options.evaluate_3d) {
    const std::vector<std::string> images = SceneImages(paths.images_dir);
    if (!images.empty()) {
      views = SceneViewDirections(images, truth_mesh.crs);
      spdlog::info("eval: {} views for the seen facades", images.size());
    }
  }
  const TriangleMesh initial_mesh = options.evaluate_3d ? MeshFromDsm(initial_dsm) : TriangleMesh{};
  s.initial = EvaluateSurface(initial_dsm, initial_mesh, truth_dsm, mask, &truth_mesh, options, &views);
  spdlog::info("eval: result surface ({} faces)", result.num_faces());
  const Dsm result_dsm = DsmFromMesh(result, truth_dsm);
  s.result = EvaluateSurface(result_dsm, result, truth_dsm, mask, &truth_mesh, options, &views);
  if (options.evaluate_3d)
    s.error_by_sigma = ErrorBySigma(result, truth_mesh, options.mesh3d.crop_xmin,
                                    options.mesh3d.crop_xmax, options.mesh3d.crop_ymin,
                                    options.mesh3d.crop_ymax);
  return s;
}

}  // namespace satmesh
