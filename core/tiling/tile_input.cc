#include "core/tiling/tile_input.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>

#include "core/common/error.h"
#include "core/dsm/fill_holes.h"
#include "core/geo/crs.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"

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
  const CrsTransform geo_from_dsm(dsm.crs_wkt, kWgs84Geographic3D);
  TriangleMesh mesh = MeshFromDsm(DownsampleDsm(dsm, factor));
  std::vector<Eigen::Vector3d> points(mesh.vertices.size());
  for (size_t i = 0; i < points.size(); ++i) points[i] = mesh.AbsoluteVertex(i);
  geo_from_dsm.Apply(&points);
  mesh.origin.setZero();
  mesh.crs.clear();
  for (size_t i = 0; i < points.size(); ++i)
    mesh.vertices[i] = frame.LocalFromGeo(points[i]).cast<float>();
  return mesh;
}

}  // namespace

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

int TileWindowMarginPx(const RefineOptions& options, double cell_m) {
  return 8 + 4 * (1 << ResolveLevels(options, cell_m, cell_m));
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

TileInput PrepareTileInput(const JobSpec& spec, Dsm dsm, double coarse_cell_m) {
  TileInput tile;
  tile.filled_dsm_cells = FillDsmHoles(&dsm, spec.fill_holes_m);
  tile.dsm_crs_wkt = dsm.crs_wkt;
  std::vector<float> valid;
  for (float z : dsm.z)
    if (std::isfinite(z)) valid.push_back(z);
  SATMESH_CHECK(!valid.empty(), ErrorCode::kInvalidInput,
                "initial DSM '" + spec.initial_dsm + "' has no valid cell");
  const auto [zmin_it, zmax_it] = std::minmax_element(valid.begin(), valid.end());
  const double h_min = *zmin_it, h_max = *zmax_it, h_mid = Median(valid);

  // Local frame at the DSM centre.
  const CrsTransform geo_from_dsm(dsm.crs_wkt, kWgs84Geographic3D);
  const double x0 = dsm.geo_transform[0], y0 = dsm.geo_transform[3];
  const double x1 = x0 + dsm.width * dsm.geo_transform[1], y1 = y0 + dsm.height * dsm.geo_transform[5];
  const Eigen::Vector3d center_geo = geo_from_dsm.Apply(Eigen::Vector3d(0.5 * (x0 + x1), 0.5 * (y0 + y1), h_mid));
  tile.refine.frame = LocalFrame(center_geo);
  tile.refine.min_z = h_min - h_mid;
  tile.refine.max_z = h_max - h_mid;

  // The tile's 3D box, geodetic, for the image windows.
  std::vector<Eigen::Vector3d> box_geo;
  for (double fx : {0.0, 0.5, 1.0})
    for (double fy : {0.0, 0.5, 1.0})
      for (double h : {h_min - 2, h_max + 2})
        box_geo.push_back(geo_from_dsm.Apply(Eigen::Vector3d(x0 + fx * (x1 - x0), y0 + fy * (y1 - y0), h)));

  const double cell_m = std::abs(dsm.geo_transform[1]);
  tile.refine.initial_cell_m = cell_m;
  // Window margin for the coarsest level's pixels (the GSD is not known yet: the DSM's cell
  // stands in for it, as in CoarseCellSize).
  const int margin_px = TileWindowMarginPx(spec.refine, cell_m);
  for (const auto& image : spec.images) {
    const RpcModel rpc = ReadRpc(image.path).WithBias(image.bias_col_row_px);
    const RasterInfo info = ReadRasterInfo(image.path);
    const PixelWindow window = ImageWindowSeeing(rpc, box_geo, info, margin_px);
    if (window.width < 16 || window.height < 16) {
      spdlog::info("image '{}' does not see the area; dropped", image.path);
      tile.dropped_views.push_back(image.path);
      continue;
    }
    RefineView view;
    view.name = image.path;
    view.image = ReadImageWindow(image.path, 1, window);
    tile.image_bytes += double(window.width) * window.height * sizeof(float);
    view.rpc = rpc.Cropped(Eigen::Vector2d(window.col0, window.row0));
    view.acquisition = ReadAcquisitionInfo(image.path);
    tile.refine.views.push_back(std::move(view));
    tile.view_names.push_back(image.path);
  }

  // Initial mesh: the DSM at the coarse cell size, into the local frame; finer levels
  // that restart from the initial surface mesh it at half their triangle edge.
  const auto cell_factor = [cell_m](double size_m) {
    return std::max(1, int(std::floor(size_m / cell_m)));
  };
  tile.refine.initial_mesh = DsmMeshInFrame(dsm, cell_factor(coarse_cell_m), tile.refine.frame);
  tile.refine.initial_for_edge = [dsm = std::make_shared<const Dsm>(dsm), cell_factor,
                                  frame = tile.refine.frame](double edge_m) {
    return DsmMeshInFrame(*dsm, cell_factor(0.5 * edge_m), frame);
  };
  return tile;
}

double CoarseCellSize(const RefineOptions& options, double dsm_cell_m) {
  return 0.5 * options.coarse_edge_px * dsm_cell_m *
         std::ldexp(1.0, ResolveLevels(options, dsm_cell_m, dsm_cell_m));
}

TileInput PrepareTileInput(const JobSpec& spec, const JobPlan& plan, int tile_index) {
  SATMESH_CHECK(tile_index >= 0 && tile_index < int(plan.tiles.size()), ErrorCode::kInvalidArgument,
                "tile index " + std::to_string(tile_index) + " out of range");
  const PlannedTile& t = plan.tiles[tile_index];
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
