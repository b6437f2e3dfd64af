#include "core/tiling/tile_run.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>

#include "core/common/memory.h"
#include "core/common/stage_time.h"
#include "core/dsm/dsm.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_io.h"
#include "core/raycast/ray_scene.h"
#include "core/tiling/memory_budget.h"
#include "core/tiling/tile_input.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

constexpr const char* kEcef = "EPSG:4978";

TriangleMesh ToTriangleMesh(const PointMesh& m, const std::string& crs) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : m.points) centroid += p;
  centroid /= double(std::max<size_t>(1, m.points.size()));
  TriangleMesh out;
  out.origin = centroid.array().round().matrix();
  out.crs = crs;
  out.faces = m.faces;
  out.height_sigma = m.height_sigma;
  out.vertices.reserve(m.points.size());
  for (const auto& p : m.points) out.vertices.push_back((p - out.origin).cast<float>());
  return out;
}

std::vector<Eigen::Vector3d> Transformed(std::vector<Eigen::Vector3d> points, const std::string& from,
                                         const std::string& to) {
  CrsTransform(from, to).Apply(&points);
  return points;
}

// Writes through a temporary name in the same folder, then renames (atomic on POSIX); a
// failed write (a full disk) leaves neither a partial file nor the temporary behind.
template <typename WriteFn>
void WriteAtomically(const fs::path& path, WriteFn write) {
  const fs::path tmp = path.parent_path() / (path.stem().string() + ".part" + path.extension().string());
  try {
    write(tmp.string());
  } catch (...) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw;
  }
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

// Bilinear height of `dsm` at (x, y) in its CRS from the valid ones of the 4 nearest cell
// centres (weights renormalised); NaN when none is valid.
float SampleDsm(const Dsm& dsm, double x, double y) {
  const double u = (x - dsm.geo_transform[0]) / dsm.geo_transform[1] - 0.5;
  const double v = (y - dsm.geo_transform[3]) / dsm.geo_transform[5] - 0.5;
  const int i0 = int(std::floor(u)), j0 = int(std::floor(v));
  const double fu = u - i0, fv = v - j0;
  double sum = 0, weight = 0;
  for (int dj = 0; dj < 2; ++dj)
    for (int di = 0; di < 2; ++di) {
      const int i = i0 + di, j = j0 + dj;
      if (i < 0 || j < 0 || i >= dsm.width || j >= dsm.height || !std::isfinite(dsm.at(i, j))) continue;
      const double w = (di ? fu : 1 - fu) * (dj ? fv : 1 - fv) + 1e-9;
      sum += w * dsm.at(i, j);
      weight += w;
    }
  return weight > 0 ? float(sum / weight) : NAN;
}

// The .glb's per-vertex scalars for viewers: _HEIGHT, the ellipsoidal height (m),
// _CHANGE, refined minus initial DSM height at the vertex (m; 0 where the initial DSM
// had no data), and where the refinement gave one, _CONFIDENCE (ConfidenceFromHeightSigma
// at the images' GSD: 1 pinned by the images, 0 seen by none).
std::vector<VertexScalar> ViewerScalars(const PointMesh& piece_dsm, const std::vector<Eigen::Vector3d>& geo,
                                        const Dsm& initial, double gsd_m) {
  VertexScalar height{"_HEIGHT", {}}, change{"_CHANGE", {}};
  height.values.reserve(geo.size());
  change.values.reserve(geo.size());
  for (size_t i = 0; i < geo.size(); ++i) {
    height.values.push_back(float(geo[i].z()));
    const Eigen::Vector3d& p = piece_dsm.points[i];
    const float before = SampleDsm(initial, p.x(), p.y());
    change.values.push_back(std::isfinite(before) ? float(p.z() - before) : 0.f);
  }
  std::vector<VertexScalar> scalars{height, change};
  if (piece_dsm.height_sigma.size() == geo.size() && gsd_m > 0) {
    VertexScalar confidence{"_CONFIDENCE", {}};
    confidence.values.reserve(geo.size());
    for (float sigma : piece_dsm.height_sigma) {
      const float c = ConfidenceFromHeightSigma(sigma, gsd_m);
      confidence.values.push_back(std::isnan(c) ? 0.f : c);
    }
    scalars.push_back(std::move(confidence));
  }
  return scalars;
}

// The debris thresholds of a tile's piece: 1 mm plus two steps of the .glb's Draco
// position quantisation (the piece's extent / (2^bits - 1); rounding moves a vertex by
// up to sqrt(3)/2 step), so no two vertices and no face collapse in the .glb either.
MeshCleanOptions PieceCleanOptions(const PointMesh& padded, const Box2d& core) {
  double zmin = 1e300, zmax = -1e300;
  for (const auto& p : padded.points) zmin = std::min(zmin, p.z()), zmax = std::max(zmax, p.z());
  const double extent = std::max({core.width(), core.height(), zmax - zmin});
  const double step = extent / double((1 << MeshWriteOptions{}.draco_position_bits) - 1);
  MeshCleanOptions options;
  options.merge_distance_m += 2 * step;
  options.min_face_height_m += 2 * step;
  return options;
}

// Writes the trimmed piece: PLY in the output CRS, GLB in the tile's ENU frame (with
// ViewerScalars against `initial`); fills the result's region and transform.
void WritePiece(const PointMesh& piece_dsm, const PlannedTile& tile, const JobPlan& plan,
                const Dsm& initial, const fs::path& out_dir, TileResult* r) {
  const std::string& dsm_crs = plan.dsm.crs_wkt;
  PointMesh piece_out{Transformed(piece_dsm.points, dsm_crs, plan.output_crs), piece_dsm.faces,
                      piece_dsm.height_sigma};
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
  const std::vector<VertexScalar> scalars = ViewerScalars(piece_dsm, geo, initial, r->refine.gsd_m);
  WriteAtomically(out_dir / TileGlbPath(tile), [&](const std::string& p) { WriteGlb(p, glb, scalars); });
  r->core_vertices = piece_dsm.points.size();
  r->core_faces = piece_dsm.faces.size();
}

}  // namespace

std::string TileGlbPath(const PlannedTile& t) { return "tiles/" + t.Name() + ".glb"; }
std::string TilePiecePath(const PlannedTile& t) { return "tiles/" + t.Name() + ".ply"; }
std::string TileDsmPath(const PlannedTile& t) { return "tiles/" + t.Name() + ".tif"; }
std::string TileConfidencePath(const PlannedTile& t) { return "tiles/" + t.Name() + ".confidence.tif"; }

float ConfidenceFromHeightSigma(float sigma_m, double gsd_m) {
  if (std::isnan(sigma_m)) return sigma_m;
  if (!std::isfinite(sigma_m)) return 0.f;
  const double r = sigma_m / gsd_m;
  return float(1.0 / (1.0 + r * r));
}

Dsm ConfidenceFromHeightSigma(Dsm sigma, double gsd_m) {
  for (float& v : sigma.z) v = ConfidenceFromHeightSigma(v, gsd_m);
  return sigma;
}

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
    auto t0 = StageClock::now();
    TileInput input = PrepareTileInput(spec, plan, tile_index);
    r.view_names = input.view_names;
    r.dropped_views = input.dropped_views;
    r.image_mb = input.image_bytes / (1 << 20);
    r.prepare_s = SecondsSince(t0);

    t0 = StageClock::now();
    r.refine = Refine(input.refine, spec.refine, progress);
    r.view_bias_px = r.refine.view_bias_px;
    r.bias_s = r.refine.bias_s;
    r.refine_s = SecondsSince(t0);
    ReturnFreedMemory();

    t0 = StageClock::now();
    const TriangleMesh& local = r.refine.mesh;
    std::vector<Eigen::Vector3d> geo(local.vertices.size());
    for (size_t i = 0; i < geo.size(); ++i) geo[i] = input.refine.frame.GeoFromLocal(local.AbsoluteVertex(i));
    const PointMesh padded{Transformed(std::move(geo), kWgs84Geographic3D, plan.dsm.crs_wkt),
                           local.faces, local.height_sigma};
    fs::create_directories(fs::path(out_dir) / "tiles");

    // The whole refined (padded) tile as a DSM: assembly takes its core cells, seams
    // compare neighbours' overlaps. (The rasters on a thread of their own beside the
    // piece's encoding saved 0.12 s of stereo 0.5 m s1's 6.7 s for 57 MB more at the peak,
    // 348 -> 405 MB: not kept; docs/benchmarks-history.md, session 37.)
    const Dsm grid = TileGrid(plan, tile.padded_cells);
    {
      const TriangleMesh padded_mesh = ToTriangleMesh(padded, plan.dsm.crs_wkt);
      const RayScene scene(padded_mesh);  // both rasters' (one BVH, not two)
      const Dsm padded_dsm = DsmFromMesh(padded_mesh, grid, &scene);
      WriteAtomically(fs::path(out_dir) / TileDsmPath(tile),
                      [&](const std::string& p) { WriteDsm(p, padded_dsm); });
      if (!local.height_sigma.empty()) {
        const Dsm confidence = ConfidenceFromHeightSigma(
            HeightSigmaFromMesh(padded_mesh, grid, &scene), r.refine.gsd_m);
        WriteAtomically(fs::path(out_dir) / TileConfidencePath(tile),
                        [&](const std::string& p) { WriteDsm(p, confidence); });
      }
    }

    const PointMesh piece = ClipToBox(padded, tile.core, PieceCleanOptions(padded, tile.core));
    SATMESH_CHECK(!piece.faces.empty(), ErrorCode::kInvalidInput,
                  "tile " + tile.Name() + ": no refined surface inside the tile's core");
    WritePiece(piece, tile, plan, input.initial_heights, out_dir, &r);
    r.write_s = SecondsSince(t0);
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
