#pragma once
// How much memory one tile's refinement needs, known before it starts, and the budget a
// worker may use. A tile's peak is dominated by its views' per-level workspaces
// (pyramids, ray directions, hit maps, warps, ZNCC fields), which grow with the image
// windows it reads: a fixed part plus a number of bytes per full-resolution window pixel
// (measured: docs/benchmarks-history.md, "Memory budget"), plus the initial surface's cells.
#include <string>
#include <utility>
#include <vector>

#include "core/image/image_io.h"
#include "core/rpc/rpc_model.h"
#include "core/tiling/job_spec.h"
#include "core/tiling/tile_plan.h"

namespace satmesh {

// The model's constants (see docs/benchmarks-history.md, "Memory budget", for the measurements).
constexpr double kBaseMb = 150;                 // process, GDAL, Embree, fixed buffers
constexpr double kBytesPerWindowPixel = 64;     // all levels' workspaces per full-res pixel
constexpr double kBytesPerDsmCell = 320;        // the meshes of each level per DSM cell

// One worker's default budget: a quarter of the machine's physical memory, divided
// among the workers (the machine is shared; a worker's estimate is an estimate).
double DefaultMemoryBudgetMb(int workers);

// The budget a job's workers run under: spec.tiling.memory_budget_mb, or the default.
double MemoryBudgetMb(const TilingOptions& tiling);

// What the estimate needs of an image: its RPC (with the job's bias) and its size. An
// image that cannot be read is left out (the tiles that need it fail reading it).
struct ImageFootprintModel {
  RpcModel rpc;
  RasterInfo info;
};
std::vector<ImageFootprintModel> ReadImageFootprintModels(const JobSpec& spec);

// Estimates the peak of refining the grid cells `padded_cells` of the job: reads those
// cells of the initial DSM for their height range (or takes `heights`, min and max, e.g.
// of an initial mesh) and projects the box into every image (no pixels read).
TileMemoryEstimate EstimateTileMemory(const JobSpec& spec, const DsmGrid& dsm,
                                      const std::vector<ImageFootprintModel>& images,
                                      const PixelWindow& padded_cells,
                                      const std::pair<double, double>* heights = nullptr);

// "tile 0_0 needs an estimated 9120 MB (26 views, 170 Mpx of image windows) but the
// memory budget is 6000 MB per worker (<budget_from>)": the message of a refused tile;
// budget_from names the setting the budget came from.
std::string OverBudgetMessage(const std::string& what, const TileMemoryEstimate& estimate,
                              double budget_mb,
                              const std::string& budget_from = "tiling.memory_budget_mb, --memory-budget");

}  // namespace satmesh
