#include "core/tiling/job.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <thread>

#include "core/common/error.h"
#include "core/common/memory.h"
#include "core/common/stage_time.h"
#include "core/common/threads.h"
#include "core/refine/bias_estimation.h"
#include "core/tiling/input_check.h"
#include "core/tiling/tile_input.h"

namespace satmesh {
namespace {

// Overall progress over tiles refined in parallel: the mean of their fractions.
class PoolProgress {
 public:
  PoolProgress(const Progress& outer, size_t tiles) : outer_(outer), fractions_(tiles, 0.0) {}
  Progress ForTile(size_t index, const std::string& name) {
    Progress p;
    p.is_cancelled = outer_.is_cancelled;
    p.on_progress = [this, index, name](double fraction, const std::string& stage) {
      std::lock_guard<std::mutex> lock(mutex_);
      fractions_[index] = fraction;
      double sum = 0;
      for (double f : fractions_) sum += f;
      outer_.Report(sum / double(fractions_.size()), "tile " + name + ": " + stage);
    };
    return p;
  }

 private:
  const Progress& outer_;
  std::mutex mutex_;
  std::vector<double> fractions_;
};

int CentralTile(const JobPlan& plan) {
  double cx = 0, cy = 0;
  for (const PlannedTile& t : plan.tiles)
    cx += 0.5 * (t.core.xmin + t.core.xmax), cy += 0.5 * (t.core.ymin + t.core.ymax);
  cx /= double(plan.tiles.size()), cy /= double(plan.tiles.size());
  int best = 0;
  double best_d2 = 1e300;
  for (size_t i = 0; i < plan.tiles.size(); ++i) {
    const Box2d& c = plan.tiles[i].core;
    const double dx = 0.5 * (c.xmin + c.xmax) - cx, dy = 0.5 * (c.ymin + c.ymax) - cy;
    if (dx * dx + dy * dy < best_d2) best_d2 = dx * dx + dy * dy, best = int(i);
  }
  return best;
}

// The window the job's biases are estimated over: centred on the AOI, whatever the
// tiling, so that a job's biases (and with them its datum) do not change with the tile
// size or the memory budget; at most window_cells and at most `tile`'s padded size
// per side (the tiles fit the budget, so the window does). `tile` (the tile nearest the
// AOI's centre) lends it the rest of a planned tile.
PlannedTile BiasWindow(const JobPlan& plan, PlannedTile tile, int window_cells) {
  const PixelWindow& a = plan.aoi_cells;
  const int width = std::min({tile.padded_cells.width, window_cells, plan.dsm.width});
  const int height = std::min({tile.padded_cells.height, window_cells, plan.dsm.height});
  const int col0 = std::clamp(a.col0 + (a.width - width) / 2, 0, plan.dsm.width - width);
  const int row0 = std::clamp(a.row0 + (a.height - height) / 2, 0, plan.dsm.height - height);
  tile.padded_cells = PixelWindow{col0, row0, width, height};
  tile.padded = plan.dsm.BoxOf(tile.padded_cells);
  return tile;
}

}  // namespace

std::vector<Eigen::Vector2d> EstimateJobBiases(const JobSpec& spec, const JobPlan& plan,
                                               int* tile_index, const Progress& progress,
                                               int window_cells) {
  SATMESH_CHECK(!plan.tiles.empty(), ErrorCode::kInvalidArgument, "bias: the plan has no tile");
  *tile_index = CentralTile(plan);
  JobPlan window_plan = plan;  // the central tile's middle, as a plan of one tile
  window_plan.tiles = {BiasWindow(plan, plan.tiles[*tile_index], window_cells)};
  const TileInput input = PrepareTileInput(spec, window_plan, 0);
  BiasOptions options;
  options.refine = spec.refine;
  const BiasEstimate estimate = EstimateRefineBiases(input.refine, options, progress);
  std::vector<Eigen::Vector2d> bias(spec.images.size(), Eigen::Vector2d::Zero());
  for (size_t v = 0; v < input.view_names.size(); ++v)
    for (size_t i = 0; i < spec.images.size(); ++i)
      if (spec.images[i].path == input.view_names[v]) bias[i] = estimate.bias_col_row_px[v];
  return bias;
}

JobBiases EstimateJobBiasesOnce(const JobSpec& spec, const JobPlan& plan, const Progress& progress,
                                int window_cells) {
  JobBiases out;
  if (!spec.refine.estimate_bias || plan.tiles.empty()) return out;
  // One tile within the window: its own estimate is the same, without reading it twice.
  const PixelWindow& only = plan.tiles.front().padded_cells;
  if (plan.tiles.size() == 1 && only.width <= window_cells && only.height <= window_cells)
    return out;
  const auto t0 = StageClock::now();
  int index = 0;
  try {
    out.bias_px = EstimateJobBiases(spec, plan, &index, progress, window_cells);
    out.tile = plan.tiles[index].Name();
    spdlog::info("job: biases estimated once over the AOI's centre ({:.1f} s), used by {} {}",
                 SecondsSince(t0), plan.tiles.size() == 1 ? "the" : "all",
                 plan.tiles.size() == 1 ? "tile" : std::to_string(plan.tiles.size()) + " tiles");
  } catch (const Error& e) {  // e.g. the central tile has no surface: each tile estimates
    if (e.code() == ErrorCode::kCancelled) throw;
    out.bias_px.clear();
    spdlog::warn("job: biases not estimated over the AOI's centre ({}); each tile estimates its own",
                 e.what());
  }
  out.seconds = SecondsSince(t0);
  return out;
}

JobSpec TileSpec(const JobSpec& spec, const JobBiases& biases) {
  if (biases.bias_px.empty()) return spec;
  SATMESH_CHECK(biases.bias_px.size() == spec.images.size(), ErrorCode::kInternal,
                "job biases: " + std::to_string(biases.bias_px.size()) + " for " +
                    std::to_string(spec.images.size()) + " images");
  JobSpec tile_spec = spec;
  for (size_t i = 0; i < spec.images.size(); ++i) tile_spec.images[i].bias_col_row_px += biases.bias_px[i];
  tile_spec.refine.estimate_bias = false;
  return tile_spec;
}

void SetJobBiases(const JobSpec& spec, const JobBiases& biases, TileResult* tile) {
  if (biases.bias_px.empty()) return;
  tile->view_bias_px.clear();
  for (const std::string& name : tile->view_names)
    for (size_t i = 0; i < spec.images.size(); ++i)
      if (spec.images[i].path == name) tile->view_bias_px.push_back(biases.bias_px[i]);
}

std::string JobSpec::Check() const {
  if (images.size() < 2) return "images: need at least 2, got " + std::to_string(images.size());
  for (size_t i = 0; i < images.size(); ++i)
    if (images[i].path.empty()) return "images[" + std::to_string(i) + "].href is empty";
  if (initial_dsm.empty() && initial_mesh.path.empty()) return "initial: needs dsm or mesh (or both)";
  if (initial_mesh.max_faces < 1) return "initial mesh: max_faces must be >= 1";
  if (!(dsm_resolution_m >= 0 && std::isfinite(dsm_resolution_m)))
    return "outputs.dsm_resolution_m must be >= 0 (0 = the images' GSD), got " +
           std::to_string(dsm_resolution_m);
  if (!(fill_holes_m >= 0 && fill_holes_m <= 10000))
    return "initial.fill_holes_m must be in [0, 10000] m, got " + std::to_string(fill_holes_m);
  if (!aoi.polygon.empty() && aoi.polygon.size() < 3)
    return "aoi: a polygon needs >= 3 points, got " + std::to_string(aoi.polygon.size());
  const std::string tiling_problem = tiling.Check();
  if (!tiling_problem.empty()) return tiling_problem;
  const std::string refine_problem = refine.Check();
  if (!refine_problem.empty()) return "options." + refine_problem;
  return "";
}

JobOutputs AssembleJob(const JobPlan& plan, std::vector<TileResult> tiles, const std::string& out_dir) {
  SATMESH_CHECK(tiles.size() == plan.tiles.size(), ErrorCode::kInternal,
                "assembly: " + std::to_string(tiles.size()) + " tile results for " +
                    std::to_string(plan.tiles.size()) + " planned tiles");
  const auto failed = [](const TileResult& t) { return !t.ok; };
  if (std::all_of(tiles.begin(), tiles.end(), failed))
    ThrowError(tiles[0].error_code, tiles.size() == 1 ? tiles[0].error
                                                      : "every tile failed; first: " + tiles[0].name +
                                                            ": " + tiles[0].error);
  JobOutputs out;
  out.plan = plan;
  out.tiles = std::move(tiles);
  out.assembly = AssembleOutputs(out.plan, out.tiles, out_dir);
  out.mesh_path = out.assembly.mesh_path;
  out.dsm_path = out.assembly.dsm_path;
  for (const auto& t : out.tiles) out.prepare_s += t.prepare_s, out.write_s += t.write_s;
  out.write_s += out.assembly.assemble_s;
  return out;
}

JobOutputs RunJob(const JobSpec& spec, const std::string& out_dir, const Progress& progress) {
  const auto t_start = StageClock::now();
  JobOutputs out;
  out.plan = PlanJob(spec);
  CheckJobInputs(spec, out.plan);
  out.plan_s = SecondsSince(t_start);
  std::filesystem::create_directories(std::filesystem::path(out_dir) / "tiles");

  // Tiled: the biases once for the job (every tile then refines with the same RPCs).
  const size_t n = out.plan.tiles.size();
  const JobBiases biases = EstimateJobBiasesOnce(spec, out.plan, progress);
  out.job_bias_px = biases.bias_px;
  out.bias_tile = biases.tile;
  out.bias_s = biases.seconds;
  const JobSpec tile_spec = TileSpec(spec, biases);

  // Worker pool: each thread takes the next tile until none is left.
  const bool single = n == 1;
  out.workers = int(std::min<size_t>(spec.tiling.workers, n));
  out.tiles.resize(n);
  PoolProgress pool_progress(progress, n);
  std::atomic<size_t> next{0};
  std::atomic<bool> cancelled{false};
  auto worker = [&] {
    if (out.workers > 1) ShareProcessorsAmongWorkers(out.workers);
    for (size_t i = next++; i < n && !cancelled; i = next++) {
      const std::string name = out.plan.tiles[i].Name();
      try {
        out.tiles[i] = RunTile(tile_spec, out.plan, int(i), out_dir, pool_progress.ForTile(i, name), single);
      } catch (const Error&) {  // only kCancelled escapes RunTile
        cancelled = true;
      }
      if (!cancelled)
        spdlog::info("tile {} {} ({}/{})", name, out.tiles[i].ok ? "done" : "FAILED", i + 1, n);
    }
  };
  const auto t_tiles = StageClock::now();
  if (out.workers == 1) {
    worker();
  } else {  // each worker on a thread of its own, so this thread's OpenMP setting stays
    std::vector<std::thread> threads;
    for (int w = 0; w < out.workers; ++w) threads.emplace_back(worker);
    for (auto& t : threads) t.join();
  }
  out.tiles_s = SecondsSince(t_tiles);
  // The job's biases, in each tile's view order, as a tile that estimated them reports.
  for (TileResult& t : out.tiles) SetJobBiases(spec, biases, &t);
  if (cancelled || progress.Cancelled()) ThrowError(ErrorCode::kCancelled, "cancelled by the caller");

  JobOutputs assembled = AssembleJob(out.plan, std::move(out.tiles), out_dir);
  out.tiles = std::move(assembled.tiles);
  out.assembly = std::move(assembled.assembly);
  out.mesh_path = assembled.mesh_path;
  out.dsm_path = assembled.dsm_path;
  out.prepare_s = assembled.prepare_s;
  out.write_s = assembled.write_s;
  if (single && out.tiles[0].ok) {
    out.refine = out.tiles[0].refine;
    out.view_names = out.tiles[0].view_names;
  }
  out.peak_rss_mb = PeakRssMb();
  out.total_s = SecondsSince(t_start);
  progress.Report(1.0, "done");
  return out;
}

}  // namespace satmesh
