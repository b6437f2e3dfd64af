#include "core/tiling/tile_plan.h"

#include <gdal_priv.h>
#include <ogr_geometry.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <utility>

#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/geo/crs.h"
#include "core/refine/view_setup.h"
#include "core/tiling/initial_mesh.h"
#include "core/tiling/memory_budget.h"

namespace satmesh {
namespace {

struct GdalCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using GdalDatasetPtr = std::unique_ptr<GDALDataset, GdalCloser>;

GdalDatasetPtr OpenDsm(const std::string& path) {
  EnsureGdalInitialized();
  GdalDatasetPtr ds(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  SATMESH_CHECK(ds != nullptr, ErrorCode::kNotFound, "cannot open DSM '" + path + "'");
  SATMESH_CHECK(ds->GetRasterCount() >= 1, ErrorCode::kInvalidInput, "DSM '" + path + "' has no band");
  // As for images (image_io.cc, CheckBlockSize): GDAL reads whole blocks of all
  // pixel-interleaved bands; a forged header must not make it allocate gigabytes.
  int bx = 0, by = 0;
  ds->GetRasterBand(1)->GetBlockSize(&bx, &by);
  const char* interleave = ds->GetMetadataItem("INTERLEAVE", "IMAGE_STRUCTURE");
  const int samples = interleave && std::string(interleave) == "PIXEL" ? ds->GetRasterCount() : 1;
  const double block_mb = double(bx) * by * samples * 8 / (1 << 20);
  SATMESH_CHECK(block_mb <= 256, ErrorCode::kInvalidInput,
                "DSM '" + path + "': one block of " + std::to_string(bx) + "x" + std::to_string(by) + " x " +
                    std::to_string(samples) + " interleaved bands is too large to read (at most 256 MB)");
  return ds;
}

// A CRS of the job must be one GDAL/PROJ knows and reachable from the DSM's: checked when
// the job is planned (the server plans at submission), naming the job's field.
void CheckCrs(const std::string& field, const std::string& crs, const std::string& dsm_crs_wkt) {
  if (crs.empty()) return;
  try {
    CrsTransform(crs, dsm_crs_wkt);
  } catch (const Error& e) {
    ThrowError(ErrorCode::kInvalidArgument, field + ": '" + crs + "' is not a usable CRS (" + e.what() + ")");
  }
}

// The AOI polygon in the DSM's CRS, each edge densified so curved images stay close.
std::vector<Eigen::Vector2d> AoiInDsmCrs(const JobAoi& aoi, const DsmGrid& grid) {
  if (aoi.crs.empty()) return aoi.polygon;
  const CrsTransform to_dsm(aoi.crs, grid.crs_wkt);
  std::vector<Eigen::Vector3d> points;
  constexpr int kSteps = 16;
  for (size_t i = 0; i < aoi.polygon.size(); ++i) {
    const Eigen::Vector2d a = aoi.polygon[i], b = aoi.polygon[(i + 1) % aoi.polygon.size()];
    for (int s = 0; s < kSteps; ++s) {
      const Eigen::Vector2d p = a + (b - a) * (double(s) / kSteps);
      points.emplace_back(p.x(), p.y(), 0.0);
    }
  }
  to_dsm.Apply(&points);
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : points) out.emplace_back(p.x(), p.y());
  return out;
}

std::unique_ptr<OGRPolygon> MakePolygon(const std::vector<Eigen::Vector2d>& ring_points) {
  auto ring = std::make_unique<OGRLinearRing>();
  for (const auto& p : ring_points) ring->addPoint(p.x(), p.y());
  ring->closeRings();
  auto polygon = std::make_unique<OGRPolygon>();
  polygon->addRingDirectly(ring.release());
  return polygon;
}

std::vector<Eigen::Vector2d> BoxRing(const Box2d& b) {
  return {{b.xmin, b.ymin}, {b.xmax, b.ymin}, {b.xmax, b.ymax}, {b.xmin, b.ymax}};
}

PixelWindow Intersect(const PixelWindow& w, int width, int height) {
  PixelWindow out;
  out.col0 = std::max(0, w.col0);
  out.row0 = std::max(0, w.row0);
  out.width = std::max(0, std::min(width, w.col0 + w.width) - out.col0);
  out.height = std::max(0, std::min(height, w.row0 + w.height) - out.row0);
  return out;
}

// The height range of the mesh's points over `box` (+-inf when none).
std::pair<double, double> HeightsOver(const InitialMesh& mesh, const Box2d& box) {
  double lo = INFINITY, hi = -INFINITY;
  for (const auto& p : mesh.mesh.points)
    if (box.Contains(p.x(), p.y())) lo = std::min(lo, p.z()), hi = std::max(hi, p.z());
  return {lo, hi};
}

// The mesh must be where the images look: some image sees part of its bounding box (at
// heights within the image's RPC height range), else the mesh is elsewhere or its CRS is
// wrong.
void CheckMeshSeenByImages(const InitialMesh& mesh, const std::vector<ImageFootprintModel>& images) {
  const CrsTransform to_geo(mesh.crs, kWgs84Geographic3D);
  std::vector<Eigen::Vector3d> corners;
  for (int k = 0; k < 8; ++k)
    corners.push_back(to_geo.Apply(Eigen::Vector3d(k & 1 ? mesh.max.x() : mesh.min.x(),
                                                   k & 2 ? mesh.max.y() : mesh.min.y(),
                                                   k & 4 ? mesh.max.z() : mesh.min.z())));
  for (const ImageFootprintModel& image : images) {
    const RpcCoefficients& c = image.rpc.coefficients();
    const double h_lo = c.height_off - 1.5 * std::abs(c.height_scale), h_hi = c.height_off + 1.5 * std::abs(c.height_scale);
    if (mesh.max.z() < h_lo || mesh.min.z() > h_hi) continue;
    double cmin = 1e300, cmax = -1e300, rmin = 1e300, rmax = -1e300;
    for (Eigen::Vector3d g : corners) {
      g.z() = std::clamp(g.z(), h_lo, h_hi);
      const Eigen::Vector2d px = image.rpc.PixelFromGeo(g);
      cmin = std::min(cmin, px.x()), cmax = std::max(cmax, px.x());
      rmin = std::min(rmin, px.y()), rmax = std::max(rmax, px.y());
    }
    if (cmax >= 0 && rmax >= 0 && cmin <= image.info.width && rmin <= image.info.height) return;
  }
  const Eigen::Vector3d center = to_geo.Apply(0.5 * (mesh.min + mesh.max));
  char where[160];
  std::snprintf(where, sizeof where, "lon %.6f, lat %.6f, h %.1f m", center.x(), center.y(), center.z());
  ThrowError(ErrorCode::kInvalidArgument, "initial.mesh '" + mesh.file + "': outside the images' footprint (none of the " +
                                              std::to_string(images.size()) + " images sees its box, centre at " + where +
                                              ", within their RPCs' height range); wrong initial.crs?");
}

// The part of `box` that at least two images see at the mesh's mid height (their
// footprints as boxes; `box` itself when none or one image localises).
Box2d SeenByTwoImages(const Box2d& box, const InitialMesh& mesh, const std::vector<ImageFootprintModel>& images) {
  const double h = 0.5 * (mesh.min.z() + mesh.max.z());
  const CrsTransform to_plan(kWgs84Geographic3D, mesh.crs);
  std::vector<Box2d> footprints;
  for (const ImageFootprintModel& image : images) {
    Box2d f{1e300, 1e300, -1e300, -1e300};
    bool ok = true;
    for (const auto& corner : {Eigen::Vector2d(0, 0), Eigen::Vector2d(image.info.width, 0),
                               Eigen::Vector2d(image.info.width, image.info.height),
                               Eigen::Vector2d(0, image.info.height)}) {
      const auto lon_lat = image.rpc.LocalizeLonLat(corner, h);
      if (!lon_lat) { ok = false; break; }
      const Eigen::Vector3d p = to_plan.Apply(Eigen::Vector3d(lon_lat->x(), lon_lat->y(), h));
      f = {std::min(f.xmin, p.x()), std::min(f.ymin, p.y()), std::max(f.xmax, p.x()), std::max(f.ymax, p.y())};
    }
    if (ok) footprints.push_back(f);
  }
  Box2d seen{1e300, 1e300, -1e300, -1e300};
  for (size_t i = 0; i < footprints.size(); ++i)
    for (size_t j = i + 1; j < footprints.size(); ++j) {
      const Box2d& a = footprints[i];
      const Box2d& b = footprints[j];
      const Box2d both{std::max(a.xmin, b.xmin), std::max(a.ymin, b.ymin), std::min(a.xmax, b.xmax), std::min(a.ymax, b.ymax)};
      if (both.xmin >= both.xmax || both.ymin >= both.ymax) continue;
      seen = {std::min(seen.xmin, both.xmin), std::min(seen.ymin, both.ymin), std::max(seen.xmax, both.xmax),
              std::max(seen.ymax, both.ymax)};
    }
  const Box2d out{std::max(box.xmin, seen.xmin), std::max(box.ymin, seen.ymin), std::min(box.xmax, seen.xmax),
                  std::min(box.ymax, seen.ymax)};
  if (seen.xmin >= seen.xmax || out.xmin >= out.xmax || out.ymin >= out.ymax) return box;
  if (out.width() < box.width() || out.height() < box.height())
    spdlog::info("plan: the initial mesh's extent cut to the {:.0f} x {:.0f} m two images see", out.width(), out.height());
  return out;
}

// A mesh job's grid: north-up cells of spec.dsm_resolution_m (0: the images' median GSD
// at the mesh's centre) over the mesh's extent in its (planning) CRS, on multiples of
// the cell.
DsmGrid MeshGrid(const JobSpec& spec, const InitialMesh& mesh, const std::vector<ImageFootprintModel>& images) {
  double cell = spec.dsm_resolution_m;
  if (cell == 0) {
    const LocalFrame frame(CrsTransform(mesh.crs, kWgs84Geographic3D).Apply(0.5 * (mesh.min + mesh.max)));
    std::vector<double> gsd;
    for (const ImageFootprintModel& image : images) gsd.push_back(GroundSamplingDistance(image.rpc, frame));
    SATMESH_CHECK(!gsd.empty(), ErrorCode::kInvalidInput, "images: none could be read for the grid's GSD");
    std::nth_element(gsd.begin(), gsd.begin() + gsd.size() / 2, gsd.end());
    cell = gsd[gsd.size() / 2];
  }
  DsmGrid grid;
  grid.crs_wkt = mesh.crs;
  const double x0 = std::floor(mesh.min.x() / cell) * cell, y1 = std::ceil(mesh.max.y() / cell) * cell;
  grid.width = std::max(1, int(std::ceil((mesh.max.x() - x0) / cell)));
  grid.height = std::max(1, int(std::ceil((y1 - mesh.min.y()) / cell)));
  grid.geo_transform = {x0, cell, 0, y1, 0, -cell};
  spdlog::info("plan: grid of {}x{} cells of {:.3f} m over the initial mesh", grid.width, grid.height, cell);
  return grid;
}

// The tile grid over the AOI's cells, x from the west, y from the south; each tile's
// memory estimated. Tiles of the user's size (`balanced` false): `tile_cells` cells, the
// last column/row taking the remainder; a sliver under half a tile joins its neighbour
// (so edges are in [0.5, 1.5) tiles), never a tile of a few cells. Automatic tiles
// (`balanced`): as few columns and rows as tiles of at most `tile_cells` cells need, of
// equal size to a cell, so that no tile needs more memory than its neighbours (a
// 2500-cell AOI in tiles of up to 1479 cells: 1250 + 1250, not 1479 + 1021).
void CutTiles(const JobSpec& spec, const std::vector<ImageFootprintModel>& images,
              const InitialMesh* mesh, int tile_cells, bool balanced,
              JobPlan* plan_out) {
  JobPlan& plan = *plan_out;
  plan.tiles.clear();
  const PixelWindow& a = plan.aoi_cells;
  if (balanced) {
    plan.nx = std::max(1, (a.width + tile_cells - 1) / tile_cells);
    plan.ny = std::max(1, (a.height + tile_cells - 1) / tile_cells);
    plan.tile_cells = std::max((a.width + plan.nx - 1) / plan.nx, (a.height + plan.ny - 1) / plan.ny);
  } else {
    plan.tile_cells = tile_cells;
    plan.nx = std::max(1, (a.width + tile_cells / 2) / tile_cells);
    plan.ny = std::max(1, (a.height + tile_cells / 2) / tile_cells);
  }
  // Column tx spans [edge(tx), edge(tx + 1)) of the AOI's width; row ty (from the south)
  // ends `edge(ty)` cells above the AOI's south edge.
  auto edge = [&](int i, int n, int extent) {
    if (i >= n) return extent;
    return balanced ? int(int64_t(i) * extent / n) : i * tile_cells;
  };
  const auto aoi = MakePolygon(plan.aoi_polygon);
  for (int ty = 0; ty < plan.ny; ++ty) {
    for (int tx = 0; tx < plan.nx; ++tx) {
      PlannedTile tile;
      tile.x = tx, tile.y = ty;
      const int col0 = a.col0 + edge(tx, plan.nx, a.width);
      const int width = a.col0 + edge(tx + 1, plan.nx, a.width) - col0;
      const int row1 = a.row0 + a.height - edge(ty, plan.ny, a.height);  // exclusive, south edge
      const int row0 = a.row0 + a.height - edge(ty + 1, plan.ny, a.height);
      tile.core_cells = {col0, row0, width, row1 - row0};
      const int o = plan.overlap_cells;
      tile.padded_cells = Intersect({col0 - o, row0 - o, tile.core_cells.width + 2 * o,
                                     tile.core_cells.height + 2 * o}, plan.dsm.width, plan.dsm.height);
      tile.core = plan.dsm.BoxOf(tile.core_cells);
      tile.padded = plan.dsm.BoxOf(tile.padded_cells);
      if (!spec.aoi.polygon.empty() && !MakePolygon(BoxRing(tile.core))->Intersects(aoi.get())) continue;
      std::pair<double, double> heights;
      if (mesh) heights = HeightsOver(*mesh, tile.padded);
      tile.memory = EstimateTileMemory(spec, plan.dsm, images, tile.padded_cells, mesh ? &heights : nullptr);
      plan.tiles.push_back(tile);
    }
  }
}

}  // namespace

const std::vector<TilingOptionInfo>& TilingOptionTable() {
  using Range = OptionRange;
  using T = TilingOptions;
  static const std::vector<TilingOptionInfo> table = {
      {"size_m", &T::tile_size_m, Range::AtLeast(0),
       "tile core edge in DSM CRS units (m); 0: one tile over the AOI (or tiles that fit "
       "memory_budget_mb)"},
      {"overlap_m", &T::overlap_m, Range::AtLeast(0),
       "refined beyond each core edge and trimmed, m"},
      {"workers", &T::workers, Range::In(1, 256), "tiles refined at once in-process"},
      {"memory_budget_mb", &T::memory_budget_mb, Range::AtLeast(0),
       "one worker's peak memory, MB; 0: a quarter of the machine's memory / workers. With size_m 0 "
       "the AOI is tiled to fit it; a tile that cannot fit is refused"},
  };
  return table;
}

std::string TilingOptions::Check() const {
  const std::string problem = CheckOptionRanges(TilingOptionTable(), *this);
  return problem.empty() ? "" : "tiling." + problem;
}

Box2d DsmGrid::BoxOf(const PixelWindow& c) const {
  const auto& gt = geo_transform;
  return Box2d{gt[0] + c.col0 * gt[1], gt[3] + (c.row0 + c.height) * gt[5],
               gt[0] + (c.col0 + c.width) * gt[1], gt[3] + c.row0 * gt[5]};
}

int JobPlan::IndexOf(int x, int y) const {
  for (size_t i = 0; i < tiles.size(); ++i)
    if (tiles[i].x == x && tiles[i].y == y) return int(i);
  return -1;
}

DsmGrid ReadDsmGrid(const std::string& path) {
  const GdalDatasetPtr ds = OpenDsm(path);
  DsmGrid grid;
  grid.width = ds->GetRasterXSize();
  grid.height = ds->GetRasterYSize();
  SATMESH_CHECK(ds->GetGeoTransform(grid.geo_transform.data()) == CE_None, ErrorCode::kInvalidInput,
                "DSM '" + path + "' has no geotransform");
  const auto& gt = grid.geo_transform;
  SATMESH_CHECK(gt[2] == 0 && gt[4] == 0 && gt[1] > 0 && gt[5] < 0, ErrorCode::kInvalidInput,
                "DSM '" + path + "': only north-up grids are supported");
  const char* wkt = ds->GetProjectionRef();
  grid.crs_wkt = wkt ? wkt : "";
  return grid;
}

Dsm ReadDsmWindow(const std::string& path, const PixelWindow& cells) {
  const GdalDatasetPtr ds = OpenDsm(path);
  Dsm dsm;
  dsm.width = cells.width;
  dsm.height = cells.height;
  ds->GetGeoTransform(dsm.geo_transform.data());
  dsm.geo_transform[0] += cells.col0 * dsm.geo_transform[1];
  dsm.geo_transform[3] += cells.row0 * dsm.geo_transform[5];
  const char* wkt = ds->GetProjectionRef();
  dsm.crs_wkt = wkt ? wkt : "";
  dsm.z.assign(size_t(cells.width) * cells.height, std::numeric_limits<float>::quiet_NaN());
  const PixelWindow in = Intersect(cells, ds->GetRasterXSize(), ds->GetRasterYSize());
  if (in.width == 0 || in.height == 0) return dsm;
  std::vector<float> buffer(size_t(in.width) * in.height);
  GDALRasterBand* band = ds->GetRasterBand(1);
  SATMESH_CHECK(band->RasterIO(GF_Read, in.col0, in.row0, in.width, in.height, buffer.data(),
                               in.width, in.height, GDT_Float32, 0, 0, nullptr) == CE_None,
                ErrorCode::kIo, "reading a window of DSM '" + path + "' failed");
  int has_nodata = 0;
  const float nodata = float(band->GetNoDataValue(&has_nodata));
  for (int j = 0; j < in.height; ++j) {
    for (int i = 0; i < in.width; ++i) {
      const float z = buffer[size_t(j) * in.width + i];
      if (std::isfinite(z) && !(has_nodata && z == nodata))
        dsm.at(in.col0 - cells.col0 + i, in.row0 - cells.row0 + j) = z;
    }
  }
  return dsm;
}

JobPlan PlanJob(const JobSpec& spec) {
  const std::string problem = spec.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "job: " + problem);
  JobPlan plan;
  const std::vector<ImageFootprintModel> images = ReadImageFootprintModels(spec);
  std::optional<InitialMesh> read;
  if (spec.StartsFromMesh()) {
    if (!spec.output_crs.empty()) CheckCrs("outputs.crs", spec.output_crs, kWgs84Geographic3D);
    read = ReadInitialMesh(spec);
  }
  if (!spec.initial_dsm.empty()) {
    plan.dsm = ReadDsmGrid(spec.initial_dsm);
    SATMESH_CHECK(!plan.dsm.crs_wkt.empty() && !CrsIsGeographic(plan.dsm.crs_wkt),
                  ErrorCode::kInvalidInput,
                  "initial.dsm: '" + spec.initial_dsm + "' is " +
                      (plan.dsm.crs_wkt.empty() ? std::string("without a CRS")
                                                : "in a geographic CRS (degrees)") +
                      "; satmesh needs a projected CRS in metres (e.g. UTM: gdalwarp -t_srs EPSG:326zz)");
  }
  const std::string source_crs = read ? read->crs : plan.dsm.crs_wkt;
  const InitialMesh* mesh = nullptr;
  if (read) {
    plan.initial_mesh = std::make_shared<const InitialMesh>(InitialMeshIn(
        *read, spec.initial_dsm.empty() ? MeshPlanCrs(spec, *read) : plan.dsm.crs_wkt, spec.fill_holes_m));
    read.reset();
    mesh = plan.initial_mesh.get();
    CheckMeshSeenByImages(*mesh, images);
    plan.mesh_zmin = mesh->min.z();
    plan.mesh_zmax = mesh->max.z();
    if (spec.initial_dsm.empty()) plan.dsm = MeshGrid(spec, *mesh, images);
  }
  CheckCrs("outputs.crs", spec.output_crs, plan.dsm.crs_wkt);
  CheckCrs("aoi.crs", spec.aoi.crs, plan.dsm.crs_wkt);
  plan.output_crs = spec.output_crs.empty() ? CrsToWkt(source_crs) : spec.output_crs;
  const auto& gt = plan.dsm.geo_transform;
  const double cell = gt[1];
  const PixelWindow all{0, 0, plan.dsm.width, plan.dsm.height};

  // AOI -> bounding cells (cells whose centre is inside the polygon's bbox).
  plan.aoi_polygon = spec.aoi.polygon.empty() ? BoxRing(plan.dsm.BoxOf(all))
                                              : AoiInDsmCrs(spec.aoi, plan.dsm);
  if (spec.aoi.polygon.empty() && spec.initial_dsm.empty())  // a mesh beyond the images
    plan.aoi_polygon = BoxRing(SeenByTwoImages(plan.dsm.BoxOf(all), *mesh, images));
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (const auto& p : plan.aoi_polygon) {
    xmin = std::min(xmin, p.x()), xmax = std::max(xmax, p.x());
    ymin = std::min(ymin, p.y()), ymax = std::max(ymax, p.y());
  }
  const int c0 = int(std::ceil((xmin - gt[0]) / cell - 0.5)), c1 = int(std::floor((xmax - gt[0]) / cell - 0.5)) + 1;
  const int r0 = int(std::ceil((ymax - gt[3]) / gt[5] - 0.5)), r1 = int(std::floor((ymin - gt[3]) / gt[5] - 0.5)) + 1;
  plan.aoi_cells = Intersect(PixelWindow{c0, r0, c1 - c0, r1 - r0}, plan.dsm.width, plan.dsm.height);
  SATMESH_CHECK(plan.aoi_cells.width > 0 && plan.aoi_cells.height > 0,
                spec.initial_dsm.empty() ? ErrorCode::kInvalidArgument : ErrorCode::kInvalidInput,
                spec.initial_dsm.empty()
                    ? "initial.mesh '" + mesh->file + "': outside the aoi"
                    : "aoi: does not overlap the initial DSM '" + spec.initial_dsm + "'");

  plan.overlap_cells = int(std::ceil(spec.tiling.overlap_m / cell - 1e-9));
  plan.memory_budget_mb = MemoryBudgetMb(spec.tiling);
  const PixelWindow& a = plan.aoi_cells;
  const bool automatic = spec.tiling.tile_size_m == 0;
  CutTiles(spec, images, mesh,
           automatic ? std::max(a.width, a.height)
                     : std::max(1, int(std::lround(spec.tiling.tile_size_m / cell))),
           automatic, &plan);
  if (automatic) {
    // Automatic tiling: the tile edge shrinks with the square root of the share of the
    // need over the fixed part that fits, until every tile fits.
    const int min_cells = std::max(32, 2 * plan.overlap_cells);
    for (;;) {
      const auto worst = std::max_element(
          plan.tiles.begin(), plan.tiles.end(),
          [](const PlannedTile& x, const PlannedTile& y) { return x.memory.peak_mb < y.memory.peak_mb; });
      if (worst == plan.tiles.end() || worst->memory.peak_mb <= plan.memory_budget_mb) break;
      SATMESH_CHECK(plan.tile_cells > min_cells, ErrorCode::kInvalidArgument,
                    OverBudgetMessage("the job's tile " + worst->Name() + " (" +
                                          std::to_string(int(plan.tile_cells * cell)) +
                                          " m, the smallest automatic tile)",
                                      worst->memory, plan.memory_budget_mb));
      const double share = std::max(0.0, plan.memory_budget_mb - kBaseMb) /
                           std::max(1.0, worst->memory.peak_mb - kBaseMb);
      const int cells = std::clamp(int(plan.tile_cells * std::sqrt(share) * 0.95), min_cells,
                                   plan.tile_cells - 1);
      spdlog::info("plan: tile {} needs an estimated {:.0f} MB, over the {:.0f} MB budget: "
                   "tiles of {} cells", worst->Name(), worst->memory.peak_mb,
                   plan.memory_budget_mb, cells);
      plan.auto_tiled = true;
      CutTiles(spec, images, mesh, cells, /*balanced=*/true, &plan);
    }
  }
  double worst_mb = 0, worst_px = 0;
  for (const PlannedTile& t : plan.tiles)
    if (t.memory.peak_mb > worst_mb) worst_mb = t.memory.peak_mb, worst_px = t.memory.window_px;
  spdlog::info("plan: AOI {}x{} cells -> {}x{} tiles of {} cells (+{} overlap), {} kept; "
               "largest estimated peak {:.0f} MB ({:.0f} Mpx of image windows), budget {:.0f} MB",
               a.width, a.height, plan.nx, plan.ny, plan.tile_cells, plan.overlap_cells,
               plan.tiles.size(), worst_mb, worst_px / 1e6, plan.memory_budget_mb);
  return plan;
}

}  // namespace satmesh
