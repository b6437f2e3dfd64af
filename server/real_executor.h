#pragma once
// The production engine: the core tiling runner behind the JobExecutor interface.
#include "server/executor.h"
#include "server/plan_cache.h"

namespace satmesh::server {

// The tiled pipeline of core/tiling (job.h): Plan = PlanJob (DSM header only, so RunTile
// and Assemble re-plan instead of keeping state), RunTile = core RunTile into job_dir
// (tiles/<x>_<y>.glb, .ply, .tif) with the job's biases (estimated once, by the first
// tile, into job_dir/job_biases.json under job_dir/job_biases.lock: any process, any
// machine sharing job_dir), Assemble = AssembleJob (mesh.ply, dsm.tif) plus tileset.json
// and metrics.json written through proto/.
class RealExecutor : public JobExecutor {
 public:
  // tile_memory_budget_mb > 0: the budget each tile's estimated peak (memory_budget.h) is
  // checked against before it starts, MB, in place of the job's tiling.memory_budget_mb
  // (which still shapes the tiles where the plan cuts them to fit): a worker's own budget
  // (satmesh-worker --memory-budget). A tile over it fails unstarted, its record naming the
  // budget and the need. 0: the job's budget.
  explicit RealExecutor(double tile_memory_budget_mb = 0) : tile_memory_budget_mb_(tile_memory_budget_mb) {}
  ExecutionPlan Plan(const JobSpec& spec) override;
  nlohmann::json RunTile(const JobSpec& spec, const TileKey& tile, const std::string& job_dir,
                         const Progress& progress) override;
  nlohmann::json Assemble(const JobSpec& spec, const std::vector<TileKey>& tiles,
                          const std::vector<nlohmann::json>& tile_results,
                          const std::string& job_dir) override;

 private:
  double tile_memory_budget_mb_ = 0;
  PlanCache plans_;  // by job directory: the tiles of a job and its assembly share one plan
};

// Writes a minimal 3D Tiles 1.1 tileset.json listing tiles/<x>_<y>.glb under one root,
// bounding boxes from the glbs (tile-local positions). Shared with test engines.
void WriteTileset(const std::string& job_dir, const std::vector<TileKey>& tiles);
// Writes text to path through a temporary file and a rename.
void WriteFileAtomic(const std::string& path, const std::string& text);

}  // namespace satmesh::server
