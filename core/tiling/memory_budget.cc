#include "core/tiling/memory_budget.h"

#include <tuple>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/common/error.h"
#include "core/geo/crs.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"
#include "core/tiling/tile_input.h"
#include "core/tiling/tile_plan.h"

namespace satmesh {

double DefaultMemoryBudgetMb(int workers) {
  const double physical_mb =
      double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE)) / double(1 << 20);
  return 0.25 * physical_mb / double(std::max(1, workers));
}

double MemoryBudgetMb(const TilingOptions& tiling) {
  return tiling.memory_budget_mb > 0 ? tiling.memory_budget_mb : DefaultMemoryBudgetMb(tiling.workers);
}

std::vector<ImageFootprintModel> ReadImageFootprintModels(const JobSpec& spec) {
  std::vector<ImageFootprintModel> out;
  for (const JobImage& image : spec.images) {
    try {
      out.push_back({ReadRpc(image.path).WithBias(image.bias_col_row_px), ReadRasterInfo(image.path)});
    } catch (const Error&) {
      // Not counted: a tile that uses it fails reading it, with the reader's message.
    }
  }
  return out;
}

TileMemoryEstimate EstimateTileMemory(const JobSpec& spec, const DsmGrid& grid,
                                      const std::vector<ImageFootprintModel>& images,
                                      const PixelWindow& padded_cells,
                                      const std::pair<double, double>* heights) {
  TileMemoryEstimate out;
  double h_min = INFINITY, h_max = -INFINITY;
  if (heights) {
    std::tie(h_min, h_max) = *heights;
  } else {
    const Dsm dsm = ReadDsmWindow(spec.initial_dsm, padded_cells);
    for (float z : dsm.z)
      if (std::isfinite(z)) h_min = std::min<double>(h_min, z), h_max = std::max<double>(h_max, z);
  }
  out.dsm_cells = double(padded_cells.width) * padded_cells.height;
  if (std::isfinite(h_min)) {
    const Box2d box = grid.BoxOf(padded_cells);
    const CrsTransform geo_from_dsm(grid.crs_wkt, kWgs84Geographic3D);
    std::vector<Eigen::Vector3d> box_geo;
    for (double fx : {0.0, 0.5, 1.0})
      for (double fy : {0.0, 0.5, 1.0})
        for (double h : {h_min - 2.0, h_max + 2.0})
          box_geo.push_back(geo_from_dsm.Apply(Eigen::Vector3d(
              box.xmin + fx * box.width(), box.ymin + fy * box.height(), h)));
    const double cell_m = std::abs(grid.geo_transform[1]);
    const int margin_px = TileWindowMarginPx(spec.refine, cell_m, spec.StartsFromMesh());
    for (const ImageFootprintModel& image : images) {
      const PixelWindow w = ImageWindowSeeing(image.rpc, box_geo, image.info, margin_px);
      if (w.width < 16 || w.height < 16) continue;
      ++out.views;
      out.window_px += double(w.width) * w.height;
    }
  }
  out.peak_mb = kBaseMb + (kBytesPerWindowPixel * out.window_px + kBytesPerDsmCell * out.dsm_cells) /
                              double(1 << 20);
  return out;
}

std::string OverBudgetMessage(const std::string& what, const TileMemoryEstimate& e, double budget_mb,
                              const std::string& budget_from) {
  char text[400];
  std::snprintf(text, sizeof(text),
                "%s needs an estimated %.0f MB (%d views, %.1f Mpx of image windows, %.2f M DSM "
                "cells) but the memory budget is %.0f MB per worker",
                what.c_str(), e.peak_mb, e.views, e.window_px / 1e6, e.dsm_cells / 1e6, budget_mb);
  return std::string(text) + " (" + budget_from + ")";
}

}  // namespace satmesh
