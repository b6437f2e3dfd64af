#pragma once
// A test engine: plans a grid of tiles, "refines" each by sleeping in small steps
// (honouring cancellation), writes a one-triangle glb per tile and appends the tile's
// name to job_dir/completions.log, so tests can count how often each tile finished.
#include <atomic>
#include <string>

#include "server/executor.h"

namespace satmesh::server::testing {

struct StubOptions {
  int tiles_x = 2, tiles_y = 2;  // tile grid, >= 1
  int tile_ms = 50;              // time per tile, ms, >= 0
  std::string fail_tile;         // a tile name ("1_0") that fails (kInvalidInput), "" = none
};

inline StubOptions Stub(int tiles_x, int tiles_y, int tile_ms, std::string fail_tile = "") {
  StubOptions o;
  o.tiles_x = tiles_x;
  o.tiles_y = tiles_y;
  o.tile_ms = tile_ms;
  o.fail_tile = std::move(fail_tile);
  return o;
}

class StubExecutor : public JobExecutor {
 public:
  explicit StubExecutor(StubOptions options) : options_(std::move(options)) {}
  ExecutionPlan Plan(const JobSpec& spec) override;
  nlohmann::json RunTile(const JobSpec& spec, const TileKey& tile, const std::string& job_dir,
                         const Progress& progress) override;
  nlohmann::json Assemble(const JobSpec& spec, const std::vector<TileKey>& tiles,
                          const std::vector<nlohmann::json>& tile_results,
                          const std::string& job_dir) override;
  int max_concurrent() const { return max_concurrent_; }
  double last_memory_budget_mb() const { return last_memory_budget_mb_; }  // of the last Plan

 private:
  StubOptions options_;
  std::atomic<int> running_{0}, max_concurrent_{0};
  std::atomic<double> last_memory_budget_mb_{-1};
};

// Writes two tiny files under root (a.tif, b.tif, dsm.tif; content irrelevant to the
// stub) and returns a job body referencing them by relative href.
nlohmann::json MakeStubJob(const std::string& root);

}  // namespace satmesh::server::testing
