#include "core/tiling/tile_run.h"

#include <spdlog/spdlog.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>

#include "core/dsm/dsm.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_io.h"
#include "core/tiling/memory_budget.h"
#include "core/tiling/tile_input.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

constexpr const char* kEcef = "EPSG:4978";

TriangleMesh ToTriangleMesh(const PointMesh& m, const std::string& crs) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : m.points) centroid += p;
  centroid /= double(std::max<size_t>(1, m.points.size()));
  TriangleMesh out;
  out.origin = centroid.array().round().matrix();
  out.crs = crs;
  out.faces = m.faces;
  out.vertices.reserve(m.points.size());
  for (const auto& p : m.points) out.vertices.push_back((p - out.origin).cast<float>());
  return out;
}

std::vector<Eigen::Vector3d> Transformed(std::vector<Eigen::Vector3d> points, const std::string& from,
                                         const std::string& to) {
  CrsTransform(from, to).Apply(&points);
  return points;
}

// Writes through a temporary name in the same folder, then renames (atomic on POSIX).
template <typename WriteFn>
void WriteAtomically(const fs::path& path, WriteFn write) {
  const fs::path tmp = path.parent_path() / (path.stem().string() + ".part" + path.extension().string());
  write(tmp.string());
  fs::rename(tmp, path);
}

// ENU at `center` (lon, lat, h): the rotation whose columns are east, north, up in ECEF.
Eigen::Matrix3d EcefFromEnu(const Eigen::Vector3d& center_lon_lat_h) {
  const double lon = center_lon_lat_h.x() * std::numbers::pi / 180;
  const double lat = center_lon_lat_h.y() * std::numbers::pi / 180;
  Eigen::Matrix3d r;
  r.col(0) << -std::sin(lon), std::cos(lon), 0;
  r.col(1) << -std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat);
  r.col(2) << std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat);
  return r;
}

double PeakRssMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // Linux: kilobytes
}

// Writes the trimmed piece: PLY in the output CRS, GLB in the tile's ENU frame; fills the
// result's region and transform.
void WritePiece(const PointMesh& piece_dsm, const PlannedTile& tile, const JobPlan& plan,
                const fs::path& out_dir, TileResult* r) {
  const std::string& dsm_crs = plan.dsm.crs_wkt;
  PointMesh piece_out{Transformed(piece_dsm.points, dsm_crs, plan.output_crs), piece_dsm.faces};
  WriteAtomically(out_dir / TilePiecePath(tile), [&](const std::string& p) {
    WriteMesh(p, ToTriangleMesh(piece_out, plan.output_crs));
  });

  const auto geo = Transformed(piece_dsm.points, dsm_crs, kWgs84Geographic3D);
  double w = 1e300, e = -1e300, s = 1e300, n = -1e300, h0 = 1e300, h1 = -1e300;
  for (const auto& g : geo) {
    w = std::min(w, g.x()), e = std::max(e, g.x()), s = std::min(s, g.y()), n = std::max(n, g.y());
    h0 = std::min(h0, g.z()), h1 = std::max(h1, g.z());
  }
  // Padding: 0.1 m (Draco quantisation is ~mm), in radians ~1.6e-8.
  const double deg = std::numbers::pi / 180, pad_rad = 0.1 / 6.3e6;
  r->region = {w * deg - pad_rad, s * deg - pad_rad, e * deg + pad_rad, n * deg + pad_rad, h0 - 0.1, h1 + 0.1};

  const Eigen::Vector3d center_dsm(0.5 * (tile.core.xmin + tile.core.xmax),
                                   0.5 * (tile.core.ymin + tile.core.ymax), 0.5 * (h0 + h1));
  const Eigen::Vector3d center_geo = CrsTransform(dsm_crs, kWgs84Geographic3D).Apply(center_dsm);
  const Eigen::Vector3d center_ecef = CrsTransform(kWgs84Geographic3D, kEcef).Apply(center_geo);
  const Eigen::Matrix3d ecef_from_enu = EcefFromEnu(center_geo);
  Eigen::Matrix4d transform = Eigen::Matrix4d::Identity();
  transform.topLeftCorner<3, 3>() = ecef_from_enu;
  transform.topRightCorner<3, 1>() = center_ecef;
  for (int i = 0; i < 16; ++i) r->transform[i] = transform(i % 4, i / 4);  // column-major

  // glTF is y-up: 3D Tiles rotates (x, y, z)_gltf to (x, -z, y), so store (e, u, -n).
  const auto ecef = Transformed(geo, kWgs84Geographic3D, kEcef);
  TriangleMesh glb;
  glb.faces = piece_dsm.faces;
  glb.vertices.reserve(ecef.size());
  for (const auto& p : ecef) {
    const Eigen::Vector3d enu = ecef_from_enu.transpose() * (p - center_ecef);
    glb.vertices.emplace_back(float(enu.x()), float(enu.z()), float(-enu.y()));
  }
  WriteAtomically(out_dir / TileGlbPath(tile), [&](const std::string& p) { WriteMesh(p, glb); });
  r->core_vertices = piece_dsm.points.size();
  r->core_faces = piece_dsm.faces.size();
}

}  // namespace

std::string TileGlbPath(const PlannedTile& t) { return "tiles/" + t.Name() + ".glb"; }
std::string TilePiecePath(const PlannedTile& t) { return "tiles/" + t.Name() + ".ply"; }
std::string TileDsmPath(const PlannedTile& t) { return "tiles/" + t.Name() + ".tif"; }

TileResult RunTile(const JobSpec& spec, const JobPlan& plan, int tile_index,
                   const std::string& out_dir, const Progress& progress, bool keep_mesh) {
  TileResult r;
  r.index = tile_index;
  try {
    SATMESH_CHECK(tile_index >= 0 && tile_index < int(plan.tiles.size()), ErrorCode::kInvalidArgument,
                  "tile index " + std::to_string(tile_index) + " out of range");
    const PlannedTile& tile = plan.tiles[tile_index];
    r.name = tile.Name();
    r.estimated_peak_mb = tile.memory.peak_mb;
    SATMESH_CHECK(tile.memory.peak_mb <= plan.memory_budget_mb || plan.memory_budget_mb <= 0,
                  ErrorCode::kInvalidArgument,
                  OverBudgetMessage("tile " + tile.Name(), tile.memory, plan.memory_budget_mb));
    auto t0 = Clock::now();
    TileInput input = PrepareTileInput(spec, plan, tile_index);
    r.view_names = input.view_names;
    r.dropped_views = input.dropped_views;
    r.image_mb = input.image_bytes / (1 << 20);
    r.prepare_s = Seconds(t0);

    t0 = Clock::now();
    r.refine = Refine(input.refine, spec.refine, progress);
    r.view_bias_px = r.refine.view_bias_px;
    r.bias_s = r.refine.bias_s;
    r.refine_s = Seconds(t0);

    t0 = Clock::now();
    const TriangleMesh& local = r.refine.mesh;
    std::vector<Eigen::Vector3d> geo(local.vertices.size());
    for (size_t i = 0; i < geo.size(); ++i) geo[i] = input.refine.frame.GeoFromLocal(local.AbsoluteVertex(i));
    const PointMesh padded{Transformed(std::move(geo), kWgs84Geographic3D, plan.dsm.crs_wkt), local.faces};
    fs::create_directories(fs::path(out_dir) / "tiles");

    // The whole refined (padded) tile as a DSM: assembly takes its core cells, seams
    // compare neighbours' overlaps.
    Dsm grid;
    grid.width = tile.padded_cells.width;
    grid.height = tile.padded_cells.height;
    grid.geo_transform = plan.dsm.geo_transform;
    grid.geo_transform[0] += tile.padded_cells.col0 * grid.geo_transform[1];
    grid.geo_transform[3] += tile.padded_cells.row0 * grid.geo_transform[5];
    grid.crs_wkt = plan.dsm.crs_wkt;
    grid.z.assign(size_t(grid.width) * grid.height, 0.f);
    const Dsm padded_dsm = DsmFromMesh(ToTriangleMesh(padded, plan.dsm.crs_wkt), grid);
    WriteAtomically(fs::path(out_dir) / TileDsmPath(tile), [&](const std::string& p) { WriteDsm(p, padded_dsm); });

    const PointMesh piece = ClipToBox(padded, tile.core);
    SATMESH_CHECK(!piece.faces.empty(), ErrorCode::kInvalidInput,
                  "tile " + tile.Name() + ": no refined surface inside the tile's core");
    WritePiece(piece, tile, plan, out_dir, &r);
    r.write_s = Seconds(t0);
    if (!keep_mesh) r.refine.mesh = TriangleMesh{};
    r.ok = true;
  } catch (const Error& e) {
    if (e.code() == ErrorCode::kCancelled) throw;
    r.error_code = e.code();
    r.error = e.what();
  } catch (const std::exception& e) {
    r.error_code = ErrorCode::kInternal;
    r.error = e.what();
  }
  r.peak_rss_mb = PeakRssMb();
  if (!r.ok) spdlog::warn("tile {} failed: {}", r.name, r.error);
  else spdlog::info("tile {}: estimated peak {:.0f} MB, process peak so far {:.0f} MB", r.name,
                    r.estimated_peak_mb, r.peak_rss_mb);
  return r;
}

}  // namespace satmesh
