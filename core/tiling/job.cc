#include "core/tiling/job.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_io.h"
#include "core/tiling/tile_input.h"

namespace satmesh {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// The refined mesh from the local frame into `crs`, origin at its rounded centroid.
TriangleMesh MeshInCrs(const TriangleMesh& local, const LocalFrame& frame, const std::string& crs) {
  std::vector<Eigen::Vector3d> points(local.vertices.size());
  for (size_t i = 0; i < points.size(); ++i)
    points[i] = frame.GeoFromLocal(local.vertices[i].cast<double>());
  CrsTransform(kWgs84Geographic3D, crs).Apply(&points);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= std::max<size_t>(1, points.size());
  TriangleMesh out;
  out.origin = centroid.array().round().matrix();
  out.crs = crs;
  out.faces = local.faces;
  out.vertices.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) out.vertices[i] = (points[i] - out.origin).cast<float>();
  return out;
}

}  // namespace

std::string JobSpec::Check() const {
  if (images.size() < 2) return "images: need at least 2, got " + std::to_string(images.size());
  for (size_t i = 0; i < images.size(); ++i)
    if (images[i].path.empty()) return "images[" + std::to_string(i) + "].href is empty";
  if (initial_dsm.empty()) return "initial.dsm is required";
  const std::string refine_problem = refine.Check();
  if (!refine_problem.empty()) return "options." + refine_problem;
  return "";
}

JobOutputs RunJob(const JobSpec& spec, const std::string& out_dir, const Progress& progress) {
  const std::string problem = spec.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "job: " + problem);
  JobOutputs out;
  auto t0 = Clock::now();
  const Dsm dsm = ReadDsm(spec.initial_dsm);
  const double cell = std::abs(dsm.geo_transform[1]);
  const double coarse_cell =
      0.5 * spec.refine.coarse_edge_px * cell * std::ldexp(1.0, spec.refine.levels);
  TileInput tile = PrepareTileInput(spec, dsm, coarse_cell);
  out.view_names = tile.view_names;
  out.prepare_s = Seconds(t0);
  spdlog::info("job: {} views, initial mesh {} vertices ({:.1f} s to prepare)",
               tile.refine.views.size(), tile.refine.initial_mesh.num_vertices(), out.prepare_s);

  out.refine = Refine(tile.refine, spec.refine, progress);

  t0 = Clock::now();
  std::filesystem::create_directories(out_dir);
  const std::string output_crs = spec.output_crs.empty() ? dsm.crs_wkt : spec.output_crs;
  const TriangleMesh mesh_out = MeshInCrs(out.refine.mesh, tile.refine.frame, output_crs);
  out.mesh_path = (std::filesystem::path(out_dir) / "mesh.ply").string();
  WriteMesh(out.mesh_path, mesh_out);
  const TriangleMesh mesh_dsm_crs = MeshInCrs(out.refine.mesh, tile.refine.frame, dsm.crs_wkt);
  out.dsm_path = (std::filesystem::path(out_dir) / "dsm.tif").string();
  WriteDsm(out.dsm_path, DsmFromMesh(mesh_dsm_crs, dsm));
  out.write_s = Seconds(t0);
  return out;
}

}  // namespace satmesh
