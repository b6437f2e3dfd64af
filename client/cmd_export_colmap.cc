// satmesh export-colmap: a job's views as a COLMAP text model of pinhole cameras fitted to
// the RPCs in the refinement's local frame, 8-bit images, the initial surface as PLY in
// that frame and frame.json to map meshes back (satmesh eval --frame). For running
// frame-camera refinements (OpenMVS RefineMesh through InterfaceCOLMAP) on the same input
// as satmesh: tests/bench/openmvs_side_by_side.sh.
//
// DIR/sparse/{cameras,images,points3D}.txt, DIR/images/img_NN.png, DIR/initial.ply,
// DIR/frame.json. The views are the image windows satmesh refine reads for the job (one
// tile, PrepareJobInput), with the job's RPC biases applied and no bias estimated.
#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "client/args.h"
#include "client/bench_support.h"
#include "client/command.h"
#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/image/image.h"
#include "core/image/image_io.h"
#include "core/mesh/mesh_io.h"
#include "core/rpc/pinhole_fit.h"

namespace satmesh::cli {
namespace {

namespace fs = std::filesystem;

constexpr const char* kUsage =
    "usage: satmesh export-colmap JOB.json --out DIR [--initial dsm|coarse] [--set key=value ...]\n"
    "  --out DIR          DIR/sparse/{cameras,images,points3D}.txt (COLMAP text, PINHOLE),\n"
    "                     DIR/images/img_NN.png (8-bit), DIR/initial.ply, DIR/frame.json\n"
    "  --initial dsm      the initial DSM (holes filled as refine fills them) as a grid mesh\n"
    "                     at its full resolution (default)\n"
    "  --initial coarse   the coarse mesh satmesh refine starts from\n"
    "  --set key=value    job overrides, as for satmesh refine\n"
    "Cameras, images and meshes are in the refinement's local frame (metres east, north, up\n"
    "from frame.json's centre); `satmesh eval --scene S --result MESH --frame DIR/frame.json`\n"
    "evaluates a mesh refined in it.\n";

struct ExportedView {
  std::string name;
  PinholeFitResult fit;
  int width = 0, height = 0;
};

std::ofstream OpenForWrite(const fs::path& path) {
  std::ofstream f(path);
  SATMESH_CHECK(f.good(), ErrorCode::kIo, "cannot write '" + path.string() + "'");
  return f;
}

// The box the pinholes must reproduce the RPCs in: the initial surface's extent, its
// height range +- 2 m.
void LocalBox(const RefineInput& input, Eigen::Vector3d* lo, Eigen::Vector3d* hi) {
  *lo = Eigen::Vector3d::Constant(1e300), *hi = Eigen::Vector3d::Constant(-1e300);
  for (const auto& v : input.initial_mesh.vertices) {
    *lo = lo->cwiseMin(v.cast<double>());
    *hi = hi->cwiseMax(v.cast<double>());
  }
  lo->z() = input.min_z - 2, hi->z() = input.max_z + 2;
}

ExportedView ExportView(const RefineInput& input, int index, const Eigen::Vector3d& lo,
                        const Eigen::Vector3d& hi, const fs::path& image_dir) {
  const RefineView& view = input.views[index];
  ExportedView out;
  char name[32];
  std::snprintf(name, sizeof(name), "img_%02d.png", index);
  out.name = name;
  out.width = view.image.width, out.height = view.image.height;
  const auto pixel_from_local = [&](const Eigen::Vector3d& x) {
    return view.rpc.PixelFromGeo(input.frame.GeoFromLocal(x));
  };
  out.fit = FitPinhole(pixel_from_local, lo, hi);
  WritePng((image_dir / out.name).string(), NormalizeRadiometry(view.image), 0.f, 1.f);
  spdlog::info(
      "{} ({}): {}x{} px, pinhole rms {:.4f} px, max {:.4f} px (DLT rms {:.4f} px, "
      "skew {:.1f} px; {} iterations)",
      out.name, view.name, out.width, out.height, out.fit.rms_px,
      std::max(out.fit.max_px, out.fit.max_px_half_step), out.fit.dlt_rms_px, out.fit.dlt_skew_px,
      out.fit.iterations);
  return out;
}

void WriteColmapModel(const std::vector<ExportedView>& views, const fs::path& sparse_dir) {
  std::ofstream cameras = OpenForWrite(sparse_dir / "cameras.txt");
  std::ofstream images = OpenForWrite(sparse_dir / "images.txt");
  std::ofstream points = OpenForWrite(sparse_dir / "points3D.txt");
  cameras << "# CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[] (fx fy cx cy)\n";
  images << "# IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME (cam_from_local)\n"
            "# POINTS2D[] (none)\n";
  points << "# no points: the initial surface is initial.ply\n";
  cameras.precision(17);
  images.precision(17);
  for (size_t i = 0; i < views.size(); ++i) {
    const PinholeCamera& c = views[i].fit.camera;
    const int id = int(i) + 1;
    cameras << id << " PINHOLE " << views[i].width << " " << views[i].height << " " << c.fx << " "
            << c.fy << " " << c.cx << " " << c.cy << "\n";
    const Eigen::Quaterniond q(c.cam_from_local_rotation);
    const Eigen::Vector3d& t = c.cam_from_local_translation;
    images << id << " " << q.w() << " " << q.x() << " " << q.y() << " " << q.z() << " " << t.x()
           << " " << t.y() << " " << t.z() << " " << id << " " << views[i].name << "\n\n";
  }
  SATMESH_CHECK(cameras.good() && images.good() && points.good(), ErrorCode::kIo,
                "writing the COLMAP model in '" + sparse_dir.string() + "' failed");
}

void WriteFrameJson(const RefineInput& input, const std::string& crs, const std::string& initial,
                    const std::vector<ExportedView>& views, const fs::path& path) {
  nlohmann::json j;
  j["frame"] =
      "satmesh LocalFrame (core/geo/local_frame.h): x = (lon - lon_c) * meters_per_degree_lon, "
      "y = (lat - lat_c) * meters_per_degree_lat, z = h - h_c (WGS84 ellipsoidal)";
  const Eigen::Vector3d& c = input.frame.center_lon_lat_h();
  j["center_lon_lat_h"] = {c.x(), c.y(), c.z()};
  j["meters_per_degree_lon"] = input.frame.meters_per_degree_lon();
  j["meters_per_degree_lat"] = input.frame.meters_per_degree_lat();
  j["crs"] = crs;  // where `satmesh eval --frame` maps meshes to (the scene's CRS)
  j["initial"] = {{"mesh", "initial.ply"}, {"from", initial}};
  for (const auto& v : views)
    j["images"].push_back({{"name", v.name},
                           {"width", v.width},
                           {"height", v.height},
                           {"pinhole_rms_px", v.fit.rms_px},
                           {"pinhole_max_px", std::max(v.fit.max_px, v.fit.max_px_half_step)},
                           {"dlt_rms_px", v.fit.dlt_rms_px},
                           {"dlt_skew_px", v.fit.dlt_skew_px},
                           {"iterations", v.fit.iterations}});
  std::ofstream f = OpenForWrite(path);
  f << j.dump(2) << "\n";
  SATMESH_CHECK(f.good(), ErrorCode::kIo, "writing '" + path.string() + "' failed");
}

int RunExportColmap(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || args.positionals().size() != 1 || !args.Has("out")) {
    std::fputs(kUsage, args.Has("help") ? stdout : stderr);
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  const std::string initial = args.GetOr("initial", "dsm");
  SATMESH_CHECK(initial == "dsm" || initial == "coarse", ErrorCode::kInvalidArgument,
                "--initial must be dsm or coarse, got '" + initial + "'");
  EnsureGdalInitialized();
  const JobSpec spec = ReadJobWithOverrides(args.positionals()[0], args.GetAll("set"));
  SATMESH_CHECK(!spec.initial_dsm.empty(), ErrorCode::kInvalidArgument,
                "export-colmap needs a job with an initial DSM (initial.dsm)");
  const TileInput tile = PrepareJobInput(spec);
  const RefineInput& input = tile.refine;

  const fs::path out = args.Require("out");
  fs::create_directories(out / "sparse");
  fs::create_directories(out / "images");
  Eigen::Vector3d lo, hi;
  LocalBox(input, &lo, &hi);
  std::vector<ExportedView> views;
  for (int i = 0; i < int(input.views.size()); ++i)
    views.push_back(ExportView(input, i, lo, hi, out / "images"));
  WriteColmapModel(views, out / "sparse");

  TriangleMesh mesh =
      initial == "dsm" ? input.initial_for_edge(2 * input.initial_cell_m) : input.initial_mesh;
  MeshWriteOptions ply;
  ply.ply_double = false;  // frame coordinates are small; frame-camera tools read floats
  WriteMesh((out / "initial.ply").string(), mesh, ply);
  WriteFrameJson(input, spec.output_crs.empty() ? tile.dsm_crs_wkt : spec.output_crs, initial,
                 views, out / "frame.json");
  double worst = 0;
  for (const auto& v : views) worst = std::max({worst, v.fit.max_px, v.fit.max_px_half_step});
  std::printf(
      "export-colmap: %zu views (pinholes within %.3f px of the RPCs), initial mesh "
      "%zu faces (%s), in %s\n",
      views.size(), worst, mesh.faces.size(), initial.c_str(), out.string().c_str());
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("export-colmap",
                         "a job's views as pinhole cameras (COLMAP text), 8-bit images and the "
                         "initial surface, in the local frame",
                         RunExportColmap);

}  // namespace satmesh::cli
