#include "core/tiling/tile_input.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/dsm/fill_holes.h"
#include "core/geo/crs.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"
#include "core/tiling/initial_mesh.h"

namespace satmesh {
namespace {

double Median(std::vector<float> values) {
  if (values.empty()) return 0;
  auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

// The DSM, block-averaged by `factor`, as a mesh in `frame`.
TriangleMesh DsmMeshInFrame(const Dsm& dsm, int factor, const LocalFrame& frame) {
  return MeshInFrame(MeshFromDsm(DownsampleDsm(dsm, factor)), dsm.crs_wkt, frame);
}

}  // namespace

TriangleMesh MeshInFrame(TriangleMesh mesh, const std::string& crs, const LocalFrame& frame) {
  std::vector<Eigen::Vector3d> points(mesh.vertices.size());
  for (size_t i = 0; i < points.size(); ++i) points[i] = mesh.AbsoluteVertex(i);
  CrsTransform(crs, kWgs84Geographic3D).Apply(&points);
  mesh.origin.setZero();
  mesh.crs.clear();
  for (size_t i = 0; i < points.size(); ++i)
    mesh.vertices[i] = frame.LocalFromGeo(points[i]).cast<float>();
  return mesh;
}

PixelWindow ImageWindowSeeing(const RpcModel& rpc, const std::vector<Eigen::Vector3d>& box_geo,
                         const RasterInfo& info, int margin_px) {
  double cmin = 1e300, cmax = -1e300, rmin = 1e300, rmax = -1e300;
  for (const auto& p : box_geo) {
    const Eigen::Vector2d px = rpc.PixelFromGeo(p);
    cmin = std::min(cmin, px.x()), cmax = std::max(cmax, px.x());
    rmin = std::min(rmin, px.y()), rmax = std::max(rmax, px.y());
  }
  PixelWindow w;
  w.col0 = std::max(0, int(std::floor(cmin)) - margin_px);
  w.row0 = std::max(0, int(std::floor(rmin)) - margin_px);
  const int c1 = std::min(info.width, int(std::ceil(cmax)) + margin_px);
  const int r1 = std::min(info.height, int(std::ceil(rmax)) + margin_px);
  w.width = std::max(0, c1 - w.col0);
  w.height = std::max(0, r1 - w.row0);
  return w;
}

int TileWindowMarginPx(const RefineOptions& options, double cell_m, bool initial_is_mesh) {
  return 8 + 4 * (1 << ResolveLevels(options, cell_m, cell_m, initial_is_mesh));
}

Dsm DownsampleDsm(const Dsm& dsm, int factor) {
  if (factor <= 1) return dsm;
  Dsm out;
  out.width = (dsm.width + factor - 1) / factor;
  out.height = (dsm.height + factor - 1) / factor;
  out.crs_wkt = dsm.crs_wkt;
  out.geo_transform = dsm.geo_transform;
  out.geo_transform[1] *= factor;
  out.geo_transform[5] *= factor;
  out.z.assign(size_t(out.width) * out.height, std::nanf(""));
  for (int j = 0; j < out.height; ++j) {
    for (int i = 0; i < out.width; ++i) {
      double sum = 0;
      int n = 0;
      for (int jj = j * factor; jj < std::min(dsm.height, (j + 1) * factor); ++jj)
        for (int ii = i * factor; ii < std::min(dsm.width, (i + 1) * factor); ++ii)
          if (std::isfinite(dsm.at(ii, jj))) sum += dsm.at(ii, jj), ++n;
      if (n > 0) out.at(i, j) = float(sum / n);
    }
  }
  return out;
}

namespace {

// The local frame at (x, y, h_mid) of `crs`, the height range, and every image window that
// sees the box [x0, x1] x [y0, y1] x [h_min - 2, h_max + 2] of `crs` (read, RPC cropped).
void FrameAndViews(const JobSpec& spec, const std::string& crs, const Box2d& box, double h_min,
                   double h_max, double h_mid, double cell_m, TileInput* tile) {
  const CrsTransform geo_from_crs(crs, kWgs84Geographic3D);
  const Eigen::Vector3d center_geo = geo_from_crs.Apply(
      Eigen::Vector3d(0.5 * (box.xmin + box.xmax), 0.5 * (box.ymin + box.ymax), h_mid));
  tile->refine.frame = LocalFrame(center_geo);
  tile->refine.min_z = h_min - h_mid;
  tile->refine.max_z = h_max - h_mid;

  // The tile's 3D box, geodetic, for the image windows.
  std::vector<Eigen::Vector3d> box_geo;
  for (double fx : {0.0, 0.5, 1.0})
    for (double fy : {0.0, 0.5, 1.0})
      for (double h : {h_min - 2, h_max + 2})
        box_geo.push_back(geo_from_crs.Apply(
            Eigen::Vector3d(box.xmin + fx * box.width(), box.ymin + fy * box.height(), h)));

  // Window margin for the coarsest level's pixels (the GSD is not known yet: the grid's
  // cell stands in for it, as in CoarseCellSize).
  const int margin_px = TileWindowMarginPx(spec.refine, cell_m, spec.StartsFromMesh());
  for (const auto& image : spec.images) {
    const RpcModel rpc = ReadRpc(image.path).WithBias(image.bias_col_row_px);
    const RasterInfo info = ReadRasterInfo(image.path);
    const PixelWindow window = ImageWindowSeeing(rpc, box_geo, info, margin_px);
    if (window.width < 16 || window.height < 16) {
      spdlog::info("image '{}' does not see the area; dropped", image.path);
      tile->dropped_views.push_back(image.path);
      continue;
    }
    RefineView view;
    view.name = image.path;
    view.image = ReadImageWindow(image.path, 1, window);
    tile->image_bytes += double(window.width) * window.height * sizeof(float);
    view.rpc = rpc.Cropped(Eigen::Vector2d(window.col0, window.row0));
    view.acquisition = ReadAcquisitionInfo(image.path);
    tile->refine.views.push_back(std::move(view));
    tile->view_names.push_back(image.path);
  }
}

Box2d BoxOfDsm(const Dsm& dsm) {
  const double x0 = dsm.geo_transform[0], y0 = dsm.geo_transform[3];
  const double x1 = x0 + dsm.width * dsm.geo_transform[1], y1 = y0 + dsm.height * dsm.geo_transform[5];
  return Box2d{std::min(x0, x1), std::min(y0, y1), std::max(x0, x1), std::max(y0, y1)};
}

TriangleMesh ToMesh(const PointMesh& m, const std::string& crs) {
  TriangleMesh out;
  out.crs = crs;
  out.faces = m.faces;
  if (!m.points.empty()) out.origin = m.points.front().array().round().matrix();
  for (const auto& p : m.points) out.vertices.push_back((p - out.origin).cast<float>());
  return out;
}

// Appends the DSM's cells where `mesh` (in the DSM's CRS) has no surface, as a mesh of
// its own (the two meet with a gap of up to a cell; the coarse remeshing keeps both).
size_t AppendDsmWhereNoMesh(Dsm dsm, PointMesh* mesh) {
  const Dsm covered = DsmFromMesh(ToMesh(*mesh, dsm.crs_wkt), dsm);
  size_t filled = 0;
  for (size_t i = 0; i < dsm.z.size(); ++i)
    if (std::isfinite(covered.z[i])) dsm.z[i] = NAN;
    else filled += std::isfinite(dsm.z[i]);
  if (filled == 0) return 0;
  const TriangleMesh extra = MeshFromDsm(dsm);
  const int base = int(mesh->points.size());
  for (size_t i = 0; i < extra.vertices.size(); ++i) mesh->points.push_back(extra.AbsoluteVertex(i));
  for (const auto& f : extra.faces) mesh->faces.push_back(f + Eigen::Vector3i::Constant(base));
  return filled;
}

}  // namespace

TileInput PrepareTileInput(const JobSpec& spec, Dsm dsm, double coarse_cell_m) {
  TileInput tile;
  double noise_m = 0;  // of the data, before the holes are filled smoothly
  const double mesh_cell_m = InitialMeshCell(spec.refine, dsm, coarse_cell_m, &noise_m);
  const double cell_m = std::abs(dsm.geo_transform[1]);
  std::string meshed = "meshed at its cells";
  if (mesh_cell_m < coarse_cell_m)
    meshed =
        fmt::format("{}, meshed at its {:.2f} m cells, not block-averaged to {:.2f} m",
                    spec.refine.trusted_initial > 0 ? "trusted" : "sharp", cell_m, coarse_cell_m);
  else if (mesh_cell_m > cell_m)
    meshed = fmt::format("block-averaged to {:.2f} m", mesh_cell_m);
  spdlog::info("initial DSM: height noise at one cell {:.3f} m ({:.2f} cell): {}", noise_m,
               noise_m / cell_m, meshed);
  coarse_cell_m = mesh_cell_m;
  tile.initial_heights = dsm;
  tile.filled_dsm_cells = FillDsmHoles(&dsm, spec.fill_holes_m);
  tile.dsm_crs_wkt = dsm.crs_wkt;
  std::vector<float> valid;
  for (float z : dsm.z)
    if (std::isfinite(z)) valid.push_back(z);
  SATMESH_CHECK(!valid.empty(), ErrorCode::kInvalidInput,
                "initial DSM '" + spec.initial_dsm + "' has no valid cell");
  const auto [zmin_it, zmax_it] = std::minmax_element(valid.begin(), valid.end());
  FrameAndViews(spec, dsm.crs_wkt, BoxOfDsm(dsm), *zmin_it, *zmax_it, Median(valid), cell_m, &tile);
  tile.refine.initial_cell_m = cell_m;

  // Initial mesh: the DSM at the coarse cell size, into the local frame; finer levels
  // that restart from the initial surface mesh it at half their triangle edge.
  const auto cell_factor = [cell_m](double size_m) {
    return std::max(1, int(std::floor(size_m / cell_m)));
  };
  tile.refine.initial_mesh = DsmMeshInFrame(dsm, cell_factor(coarse_cell_m), tile.refine.frame);
  tile.refine.initial_mesh_cell_m = cell_factor(coarse_cell_m) * cell_m;
  tile.refine.initial_for_edge = [dsm = std::make_shared<const Dsm>(dsm), cell_factor,
                                  frame = tile.refine.frame](double edge_m) {
    return DsmMeshInFrame(*dsm, cell_factor(0.5 * edge_m), frame);
  };
  return tile;
}

Dsm TileGrid(const JobPlan& plan, const PixelWindow& cells) {
  Dsm grid;
  grid.width = cells.width;
  grid.height = cells.height;
  grid.geo_transform = plan.dsm.geo_transform;
  grid.geo_transform[0] += cells.col0 * grid.geo_transform[1];
  grid.geo_transform[3] += cells.row0 * grid.geo_transform[5];
  grid.crs_wkt = plan.dsm.crs_wkt;
  grid.z.assign(size_t(grid.width) * grid.height, NAN);
  return grid;
}

namespace {

// A mesh job's tile: the initial mesh (in the plan's CRS) clipped to the padded box, 3D
// kept; with a DSM too, its cells where the mesh has no surface added.
TileInput PrepareMeshTileInput(const JobSpec& spec, const JobPlan& plan, const PlannedTile& t) {
  TileInput tile;
  const std::string& crs = plan.dsm.crs_wkt;
  tile.dsm_crs_wkt = crs;
  // The plan's (PlanJob made it once for the job), else made here (a plan from elsewhere).
  std::shared_ptr<const InitialMesh> mesh = plan.initial_mesh;
  if (!mesh || mesh->crs != crs)
    mesh = std::make_shared<const InitialMesh>(InitialMeshIn(ReadInitialMesh(spec), crs, spec.fill_holes_m));
  PointMesh piece = ClipInitialMesh(*mesh, t.padded);
  if (!spec.initial_dsm.empty()) {
    Dsm dsm = ReadDsmWindow(spec.initial_dsm, t.padded_cells);
    FillDsmHoles(&dsm, spec.fill_holes_m);
    tile.filled_dsm_cells = AppendDsmWhereNoMesh(std::move(dsm), &piece);
  }
  SATMESH_CHECK(!piece.faces.empty(), ErrorCode::kInvalidInput,
                "tile " + t.Name() + ": the initial mesh has no surface in it");
  tile.initial_heights = DsmFromMesh(ToMesh(piece, crs), TileGrid(plan, t.padded_cells));

  std::vector<Eigen::Vector3d> geo = piece.points;
  CrsTransform(crs, kWgs84Geographic3D).Apply(&geo);
  std::vector<float> heights;
  heights.reserve(geo.size());
  for (const auto& g : geo) heights.push_back(float(g.z()));
  const auto [zmin_it, zmax_it] = std::minmax_element(heights.begin(), heights.end());
  const double cell_m = plan.dsm.geo_transform[1];
  FrameAndViews(spec, crs, t.padded, *zmin_it, *zmax_it, Median(heights), cell_m, &tile);
  tile.refine.initial_cell_m = cell_m;
  tile.refine.initial_is_mesh = true;
  TriangleMesh& initial = tile.refine.initial_mesh;  // the coarse level remeshes it
  initial.faces = std::move(piece.faces);
  initial.vertices.reserve(geo.size());
  for (const auto& g : geo) initial.vertices.push_back(tile.refine.frame.LocalFromGeo(g).cast<float>());
  const MeshDebris debris = CleanMesh(&initial);  // float frame coordinates: none expected
  if (debris.Total() > 0) spdlog::info("tile {}: initial mesh: {}", t.Name(), debris.ToString());
  return tile;
}

}  // namespace

double InitialMeshCell(const RefineOptions& options, const Dsm& dsm, double coarse_cell_m,
                       double* noise_m) {
  const double cell_m = std::abs(dsm.geo_transform[1]);
  const double noise = DsmCellNoise(dsm);
  if (noise_m) *noise_m = noise;
  const bool sharp =
      options.sharp_dsm_noise_cells > 0 && noise <= options.sharp_dsm_noise_cells * cell_m;
  return sharp || options.trusted_initial > 0 ? std::min(cell_m, coarse_cell_m) : coarse_cell_m;
}

double CoarseCellSize(const RefineOptions& options, double dsm_cell_m) {
  return 0.5 * options.coarse_edge_px * dsm_cell_m *
         std::ldexp(1.0, ResolveLevels(options, dsm_cell_m, dsm_cell_m));
}

TileInput PrepareTileInput(const JobSpec& spec, const JobPlan& plan, int tile_index) {
  SATMESH_CHECK(tile_index >= 0 && tile_index < int(plan.tiles.size()), ErrorCode::kInvalidArgument,
                "tile index " + std::to_string(tile_index) + " out of range");
  const PlannedTile& t = plan.tiles[tile_index];
  if (spec.StartsFromMesh()) return PrepareMeshTileInput(spec, plan, t);
  Dsm crop = ReadDsmWindow(spec.initial_dsm, t.padded_cells);
  const bool any_valid = std::any_of(crop.z.begin(), crop.z.end(), [](float z) { return std::isfinite(z); });
  SATMESH_CHECK(any_valid, ErrorCode::kInvalidInput,
                "tile " + t.Name() + ": the initial DSM has no valid cell in it");
  const size_t cells = crop.z.size();
  TileInput tile =
      PrepareTileInput(spec, std::move(crop), CoarseCellSize(spec.refine, plan.dsm.geo_transform[1]));
  if (tile.filled_dsm_cells > 0)
    spdlog::info("tile {}: {} empty DSM cells ({:.1f}%) filled", t.Name(), tile.filled_dsm_cells,
                 100.0 * tile.filled_dsm_cells / cells);
  return tile;
}

}  // namespace satmesh
