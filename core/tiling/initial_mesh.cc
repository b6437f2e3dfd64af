#include "core/tiling/initial_mesh.h"

#include <Eigen/Geometry>
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <utility>

#include "core/common/error.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_io.h"
#include "core/refine/fill_holes.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

void BoundingBox(InitialMesh* m) {
  m->min = Eigen::Vector3d::Constant(1e300);
  m->max = Eigen::Vector3d::Constant(-1e300);
  for (const auto& p : m->mesh.points) m->min = m->min.cwiseMin(p), m->max = m->max.cwiseMax(p);
}

std::string Where(const InitialMesh& m) { return "initial.mesh '" + m.file + "'"; }

}  // namespace

std::string InitialMeshFile(const std::string& path) {
  std::error_code ec;
  fs::path file(path);
  if (fs::is_directory(file, ec)) file /= "mesh.ply";
  else if (file.filename() == "tileset.json") file = file.parent_path() / "mesh.ply";
  SATMESH_CHECK(fs::is_regular_file(file, ec), ErrorCode::kNotFound,
                "initial.mesh: '" + path + "'" +
                    (file.string() == path ? " does not exist" : ": no " + file.string() + " (a previous job's mesh.ply)"));
  return file.string();
}

InitialMesh ReadInitialMesh(const JobSpec& spec) {
  InitialMesh out;
  out.file = InitialMeshFile(spec.initial_mesh.path);
  TriangleMesh mesh;
  try {
    mesh = ReadMesh(out.file);
  } catch (const Error& e) {
    ThrowError(e.code() == ErrorCode::kNotFound ? e.code() : ErrorCode::kInvalidArgument,
               Where(out) + ": cannot be read: " + e.what());
  }
  SATMESH_CHECK(!mesh.faces.empty(), ErrorCode::kInvalidArgument, Where(out) + ": has no faces");
  SATMESH_CHECK(mesh.faces.size() <= spec.initial_mesh.max_faces, ErrorCode::kInvalidArgument,
                Where(out) + ": " + std::to_string(mesh.faces.size()) + " faces, more than the limit of " +
                    std::to_string(spec.initial_mesh.max_faces));
  out.crs = !spec.initial_mesh.crs.empty() ? spec.initial_mesh.crs
            : !mesh.crs.empty()            ? mesh.crs
                                           : spec.output_crs;
  SATMESH_CHECK(!out.crs.empty(), ErrorCode::kInvalidArgument,
                "initial.crs: " + Where(out) + " does not say its CRS; give initial.crs or outputs.crs");
  try {
    CrsToWkt(out.crs);
  } catch (const Error& e) {
    ThrowError(ErrorCode::kInvalidArgument, "initial.crs: '" + out.crs + "' is not a usable CRS (" + e.what() + ")");
  }
  ValidateMesh(mesh, Where(out));  // ReadMesh's formats check it too
  out.mesh.faces = std::move(mesh.faces);
  out.mesh.points.reserve(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i) out.mesh.points.push_back(mesh.AbsoluteVertex(i));
  BoundingBox(&out);
  return out;
}

std::string MeshPlanCrs(const JobSpec& spec, const InitialMesh& mesh) {
  if (!spec.output_crs.empty() && CrsIsProjected(spec.output_crs)) return CrsToWkt(spec.output_crs);
  if (CrsIsProjected(mesh.crs)) return CrsToWkt(mesh.crs);
  const Eigen::Vector3d center = CrsTransform(mesh.crs, kWgs84Geographic3D).Apply(0.5 * (mesh.min + mesh.max));
  SATMESH_CHECK(center.allFinite(), ErrorCode::kInvalidInput,
                Where(mesh) + ": its centre does not transform from '" + mesh.crs + "' to WGS84");
  return CrsToWkt(UtmCrsAt(center.x(), center.y()));
}

InitialMesh InitialMeshIn(const InitialMesh& mesh, const std::string& crs, double fill_holes_m) {
  InitialMesh out = mesh;
  out.crs = crs;
  try {
    CrsTransform(mesh.crs, crs).Apply(&out.mesh.points);
  } catch (const Error&) {  // its message holds the planning CRS's whole WKT
    ThrowError(ErrorCode::kInvalidArgument, Where(mesh) + ": its points do not transform from its CRS '" +
                                             mesh.crs + "' into the job's; wrong initial.crs?");
  }
  // Seen from above, a surface's up-facing area exceeds its down-facing area (walls count
  // zero, overhangs' undersides are smaller than what covers them; a closed building
  // without ground has as much of each): more than twice as much down is inverted.
  double up = 0, down = 0;
  for (const auto& f : out.mesh.faces) {
    const auto& p = out.mesh.points;
    const double z = (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]).z();
    (z > 0 ? up : down) += std::abs(z);
  }
  SATMESH_CHECK(down <= 2 * up, ErrorCode::kInvalidArgument,
                Where(mesh) + ": its faces point down (" + std::to_string(int(100 * down / (up + down))) +
                    "% of the area seen from above; expected counter-clockwise faces seen from "
                    "outside): flip its orientation");
  // The repair in metres (the file's units may be degrees).
  out.mesh = CleanPointMesh(out.mesh, {}, &out.repaired);
  if (out.repaired.Total() > 0) spdlog::info("{}: repaired: {}", Where(out), out.repaired.ToString());
  SATMESH_CHECK(!out.mesh.faces.empty(), ErrorCode::kInvalidArgument,
                Where(out) + ": no face left after removing degenerate ones (" + out.repaired.ToString() + ")");
  if (fill_holes_m > 0) {
    const HoleFill fill = FillHoles(fill_holes_m, &out.mesh.points, &out.mesh.faces);
    if (!out.mesh.height_sigma.empty()) out.mesh.height_sigma.resize(out.mesh.points.size(), NAN);
    if (fill.filled + fill.too_big > 0)
      spdlog::info("{}: {} hole(s) up to {} m filled ({} faces), {} larger left open, {} covered "
                   "from above left", Where(out), fill.filled, fill_holes_m, fill.faces_added,
                   fill.too_big, fill.covered);
  }
  BoundingBox(&out);
  return out;
}

PointMesh ClipInitialMesh(const InitialMesh& mesh, const Box2d& box) {
  return ClipToBox(mesh.mesh, box);
}

}  // namespace satmesh
