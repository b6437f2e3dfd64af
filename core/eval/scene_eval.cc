#include "core/eval/scene_eval.h"

#include <spdlog/spdlog.h>

#include <filesystem>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
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

std::string SceneEvalOptions::Check() const {
  if (auto m = dsm.Check(); !m.empty()) return "dsm: " + m;
  if (auto m = mesh3d.Check(); !m.empty()) return "mesh3d: " + m;
  return "";
}

ScenePaths SceneLayout(const std::string& scene_dir) {
  const fs::path d(scene_dir);
  return {(d / "truth" / "mesh.ply").string(), (d / "truth" / "dsm.tif").string(),
          (d / "truth" / "roof_mask.tif").string(), (d / "initial" / "dsm.tif").string()};
}

SurfaceEvaluation EvaluateSurface(const Dsm& dsm, const TriangleMesh& mesh, const Dsm& truth_dsm,
                                  const std::vector<uint8_t>& mask, const TriangleMesh* truth_mesh,
                                  const SceneEvalOptions& options) {
  SurfaceEvaluation e;
  e.dsm = EvaluateDsm(dsm, truth_dsm, mask, options.dsm);
  if (options.evaluate_3d && truth_mesh) e.mesh3d = EvaluateMesh3d(mesh, *truth_mesh, options.mesh3d);
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
  const TriangleMesh initial_mesh = options.evaluate_3d ? MeshFromDsm(initial_dsm) : TriangleMesh{};
  s.initial = EvaluateSurface(initial_dsm, initial_mesh, truth_dsm, mask, &truth_mesh, options);
  spdlog::info("eval: result surface ({} faces)", result.num_faces());
  const Dsm result_dsm = DsmFromMesh(result, truth_dsm);
  s.result = EvaluateSurface(result_dsm, result, truth_dsm, mask, &truth_mesh, options);
  return s;
}

}  // namespace satmesh
