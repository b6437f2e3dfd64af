// satmesh eval: 2.5D and 3D metrics of a result surface on a synthetic scene, printed
// next to the scene's initial DSM (and written as JSON with --json).
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "client/args.h"
#include "client/command.h"
#include "client/eval_pictures.h"
#include "client/eval_report_format.h"
#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/eval/scene_eval.h"
#include "core/geo/crs.h"
#include "core/geo/local_frame.h"
#include "core/mesh/mesh_io.h"

namespace satmesh::cli {
namespace {

constexpr const char* kUsage =
    "usage: satmesh eval --scene DIR --result MESH_OR_DIR [--frame FRAME.json] [--json OUT]\n"
    "                    [--pictures DIR]\n"
    "  --scene DIR              synthetic scene (truth/, initial/; see satmesh synth)\n"
    "  --result PATH            result mesh (PLY/OBJ, scene CRS) or a directory with mesh.ply\n"
    "  --frame FRAME.json       the result mesh is in the local frame `satmesh export-colmap`\n"
    "                           wrote (e.g. refined by OpenMVS): mapped to the frame's CRS first\n"
    "  --json OUT               write the report as JSON\n"
    "  --samples-per-m2 D       3D surface sampling density (default 4)\n"
    "  --max-shift-m D          XY alignment search half-width (default 3)\n"
    "  --facade-max-abs-nz D    facade: |n_z| below this (default 0.3)\n"
    "  --distance-backend B     embree | cgal (default embree)\n"
    "  --align-on-mask          estimate the alignment on the roof mask only\n"
    "  --no-3d                  skip the 3D metrics\n"
    "  --pictures DIR           write DIR/height_error.png (initial and result minus the truth,\n"
    "                           one colour scale) and DIR/zncc.png (a result directory's ZNCC\n"
    "                           per iteration and level)\n"
    "  --error-range-m D        colour scale of the height error maps: +-D m (default 2)\n";

// A mesh in the local frame described by `frame_path` (written by export-colmap), mapped
// to the frame's CRS (the scene's).
TriangleMesh MeshFromFrame(const std::string& result_path, const std::string& frame_path) {
  std::ifstream in(frame_path);
  SATMESH_CHECK(in.good(), ErrorCode::kNotFound, "cannot read --frame '" + frame_path + "'");
  const nlohmann::json j = nlohmann::json::parse(in);
  const auto& c = j.at("center_lon_lat_h");
  const LocalFrame frame(
      Eigen::Vector3d(c.at(0).get<double>(), c.at(1).get<double>(), c.at(2).get<double>()));
  const std::string crs = j.at("crs").get<std::string>();
  std::string mesh_path = result_path;
  if (std::filesystem::is_directory(mesh_path)) mesh_path += "/mesh.ply";
  TriangleMesh mesh = ReadMesh(mesh_path);
  std::vector<Eigen::Vector3d> points(mesh.vertices.size());
  for (size_t i = 0; i < points.size(); ++i) points[i] = frame.GeoFromLocal(mesh.AbsoluteVertex(i));
  CrsTransform(kWgs84Geographic3D, crs).Apply(&points);
  mesh.crs = crs;
  mesh.origin.setZero();
  if (!points.empty()) mesh.origin = points.front().array().round().matrix();
  for (size_t i = 0; i < points.size(); ++i)
    mesh.vertices[i] = (points[i] - mesh.origin).cast<float>();
  return mesh;
}

int RunEval(const std::vector<std::string>& argv) {
  const Args args(argv, {"help", "align-on-mask", "no-3d"});
  if (args.Has("help")) {
    std::fputs(kUsage, stdout);
    return kExitOk;
  }
  SceneEvalOptions options;
  options.mesh3d.sampling.samples_per_m2 = args.GetDouble("samples-per-m2", 4.0);
  options.mesh3d.facade_max_abs_nz = args.GetDouble("facade-max-abs-nz", 0.3);
  options.dsm.align.max_shift_m = args.GetDouble("max-shift-m", 3.0);
  options.dsm.align_on_mask = args.Has("align-on-mask");
  options.evaluate_3d = !args.Has("no-3d");
  const std::string backend = args.GetOr("distance-backend", "embree");
  SATMESH_CHECK(backend == "embree" || backend == "cgal", ErrorCode::kInvalidArgument,
                "--distance-backend must be embree or cgal, got '" + backend + "'");
  options.mesh3d.backend =
      backend == "cgal" ? DistanceBackend::kCgalAabb : DistanceBackend::kEmbree;
  const std::string msg = options.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, msg);

  EnsureGdalInitialized();
  const auto t0 = std::chrono::steady_clock::now();
  const auto frame = args.Get("frame");
  SATMESH_CHECK(!(frame && args.Has("pictures")), ErrorCode::kInvalidArgument,
                "--pictures does not take a --frame mesh");
  const SceneEvaluation e =
      frame ? EvaluateScene(args.Require("scene"), MeshFromFrame(args.Require("result"), *frame),
                            options)
            : EvaluateScene(args.Require("scene"), args.Require("result"), options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::fputs(FormatSceneEvaluation(e).c_str(), stdout);
  spdlog::info("eval: {:.2f} s", seconds);
  if (auto out = args.Get("json")) {
    nlohmann::json j = SceneEvaluationToJson(e);
    j["scene"] = args.Require("scene");
    j["result_path"] = args.Require("result");
    std::ofstream f(*out);
    SATMESH_CHECK(f.good(), ErrorCode::kIo, "cannot write --json file '" + *out + "'");
    f << j.dump(2) << "\n";
    SATMESH_CHECK(f.good(), ErrorCode::kIo, "writing --json file '" + *out + "' failed");
  }
  if (auto dir = args.Get("pictures")) {
    for (const auto& path : WriteEvalPictures(args.Require("scene"), args.Require("result"), e,
                                              *dir, args.GetDouble("error-range-m", 2.0)))
      std::printf("picture: %s\n", path.c_str());
  }
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("eval", "2.5D and 3D metrics of a result vs. a synthetic scene's truth",
                         RunEval);

}  // namespace satmesh::cli
