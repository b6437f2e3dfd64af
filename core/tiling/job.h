#pragma once
// The job's one tile pipeline, as the CLI (RunJob, in-process), the embedded server and
// the queue's workers (server/) all run it:
//   1. plan      PlanJob (tile_plan.h) + CheckJobInputs (input_check.h); with
//                refine.estimate_bias: EstimateJobBiasesOnce, and every tile refines with
//                TileSpec (the job's biases, not its own)
//   2. tiles     RunTile (tile_run.h) for every planned tile: any order, any thread,
//                process or machine, again if need be (files written atomically)
//   3. assemble  AssembleJob (below), once, over every tile's result
// Tile failure policy (the one for every caller): a tile that fails is recorded as failed,
// with its error code and reason (TileResult::ok, error_code, error); the job's other
// tiles go on; the job is assembled from the successful tiles (a failed tile's cells stay
// nodata, the metrics count it) and fails only when no tile succeeded. Cancellation
// (Error{kCancelled}) stops every tile and the job.
#include <string>
#include <vector>

#include "core/common/progress.h"
#include "core/refine/refine.h"
#include "core/tiling/assemble.h"
#include "core/tiling/job_spec.h"
#include "core/tiling/tile_plan.h"
#include "core/tiling/tile_run.h"

namespace satmesh {

struct JobOutputs {
  JobPlan plan;
  std::vector<TileResult> tiles;   // one per planned tile, in plan order
  Assembly assembly;               // seams, tileset, paths
  std::string mesh_path, dsm_path; // out_dir/mesh.ply, out_dir/dsm.tif
  RefineResult refine;             // single-tile jobs: that tile's result (mesh in its
                                   // frame); tiled jobs: empty (see tiles[])
  std::vector<std::string> view_names;  // single-tile jobs: the views used
  int workers = 1;
  double plan_s = 0, tiles_s = 0, total_s = 0;
  double prepare_s = 0, write_s = 0;    // summed over tiles (+ assembly for write_s)
  // Tiled jobs with estimate_bias: the biases estimated once, over the tile nearest the
  // AOI's centre, and given to every tile (spec order; zero for an image that tile's
  // area does not see; each tile's view_bias_px repeats them in its view order); bias_s
  // its time (reading that tile's windows included). If that tile cannot give them (no
  // surface, no pair), empty, and every tile estimates its own as before.
  std::vector<Eigen::Vector2d> job_bias_px;
  std::string bias_tile;
  double bias_s = 0;
  double peak_rss_mb = 0;          // process peak resident memory at the end
};

// The biases are one shift per image: a central window of kBiasWindowCells^2 DSM cells
// (0.64 Mpx at the DSM's cell; at 0.3 m, 240 m square) gives them as well as a whole
// tile, at a fraction of the time (large jax scene, tile of 1539^2 cells: BENCHMARKS.md).
// Smaller windows lose accuracy where few views match (multi-date 0.3 m, 6 views, biases
// vs the truth with the datum fitted out: rms 0.081 px over 1160^2 and 800^2 cells, 0.100
// over 640^2, 0.109 over 512^2; docs/benchmarks-history.md, session 24).
constexpr int kBiasWindowCells = 800;

// The job's per-image RPC biases, estimated once over a window centred on the AOI (at
// most window_cells^2 DSM cells, and at most the padded size of the planned tile nearest the
// AOI's centre, which fits the memory budget like every tile; *tile_index is that tile),
// so that they do not depend on the tiling; in spec.images order, added to the spec's
// biases; an image the window does not see keeps its bias. Throws like RunTile for that
// window (Error; kCancelled when cancelled).
std::vector<Eigen::Vector2d> EstimateJobBiases(const JobSpec& spec, const JobPlan& plan,
                                               int* tile_index, const Progress& progress = {},
                                               int window_cells = kBiasWindowCells);

// Step 1b: the job's biases, estimated once over the AOI's centre (EstimateJobBiases).
struct JobBiases {
  std::vector<Eigen::Vector2d> bias_px;  // spec.images order; empty: each tile estimates its own
  std::string tile;                      // the tile nearest the AOI's centre (bounds the window)
  double seconds = 0;                    // their time (that tile's windows read included)
};
// Empty without refine.estimate_bias, for a one-tile job whose tile fits in the window
// (it estimates its own over the same cells), or when the window cannot give them (no
// surface, no pair; logged). A larger single tile takes them from the window too: the
// 300 m jax scene's 1160^2-cell tile spent 28 of its 72 s on them, 19 s over the window.
// Throws Error{kCancelled} when cancelled.
JobBiases EstimateJobBiasesOnce(const JobSpec& spec, const JobPlan& plan, const Progress& progress = {},
                                int window_cells = kBiasWindowCells);
// The spec every tile refines with: the job's biases added to the images', estimate_bias
// off; `spec` itself when there are none.
JobSpec TileSpec(const JobSpec& spec, const JobBiases& biases);
// A tile's view_bias_px as the job's biases in its view order (as a tile that estimated
// its own reports them); unchanged when there are none.
void SetJobBiases(const JobSpec& spec, const JobBiases& biases, TileResult* tile);

// Step 3: assembles out_dir/mesh.ply, dsm.tif and the tileset from the tiles' results
// (one per planned tile, in plan order; their files under out_dir/tiles/), and sums their
// timings into the outputs (plan, tiles, assembly, paths, prepare_s, write_s). Throws
// Error (the first tile's code) naming the first failed tile when no tile succeeded.
JobOutputs AssembleJob(const JobPlan& plan, std::vector<TileResult> tiles, const std::string& out_dir);

// Plans, refines every tile on spec.tiling.workers threads (the failure policy above), then assembles out_dir/mesh.ply,
// out_dir/dsm.tif and out_dir/tiles/. tileset.json and metrics.json are JSON: proto/
// writes them (proto::WriteJobJson). Throws Error for an invalid spec or unreadable DSM,
// Error{kCancelled} when cancelled; never for one failing tile.
JobOutputs RunJob(const JobSpec& spec, const std::string& out_dir, const Progress& progress = {});

}  // namespace satmesh
