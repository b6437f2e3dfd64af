#pragma once
// The engine behind the HTTP layer (OSRM style): handlers and the scheduler depend on this
// interface only, so tests can plug in a stub and exercise HTTP without refinement.
// Cancellation and progress arrive explicitly through Progress.
#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/progress.h"
#include "core/tiling/job.h"

namespace satmesh::server {

struct TileKey {
  int x = 0, y = 0;  // tile column, row in the job's tile grid, >= 0
  std::string Name() const { return std::to_string(x) + "_" + std::to_string(y); }
  bool operator==(const TileKey&) const = default;
};

// A tile result record's failure, from RunTile's record: false for a successful one.
// Sets *code (ErrorCodeName: "no-space", ...) and *message when failed.
bool TileRecordFailed(const nlohmann::json& record, std::string* code, std::string* message);
// The record of a tile that failed outside the engine (an exception, a dead letter).
nlohmann::json FailedTileRecord(const TileKey& tile, const std::string& code, const std::string& message);

struct ExecutionPlan {
  std::vector<TileKey> tiles;  // in processing order
  int64_t pixels = 0;          // total image pixels the job reads (limits)
};

class JobExecutor {
 public:
  virtual ~JobExecutor() = default;
  // Checks the inputs (throws Error naming the field/file) and splits the job into tiles.
  virtual ExecutionPlan Plan(const JobSpec& spec) = 0;
  // Refines one tile; writes job_dir/tiles/<x>_<y>.glb (and any per-tile work files).
  // Returns the tile's result record (proto's TileResultToJson: "status" "successful" or
  // "failed" with "error": {"code", "message"}): the scheduler persists it with the tile
  // and hands it back to Assemble (also after a restart, or on another machine). A failing
  // tile is a record, not an exception (core/tiling/job.h's failure policy: that tile
  // fails, the others go on); throws only Error{kCancelled} when progress.Cancelled()
  // turns true (any other exception is that tile's failure). Re-running a tile must be
  // harmless (files written to a temporary name and renamed).
  virtual nlohmann::json RunTile(const JobSpec& spec, const TileKey& tile,
                                 const std::string& job_dir, const Progress& progress) = 0;
  // After every tile finished (done or failed, at least one done): writes
  // job_dir/tileset.json, metrics.json (and mesh.ply, dsm.tif where the engine makes
  // them) from the successful tiles; returns the metrics. tile_results[i] is what RunTile
  // returned for tiles[i] (failed ones included).
  virtual nlohmann::json Assemble(const JobSpec& spec, const std::vector<TileKey>& tiles,
                                  const std::vector<nlohmann::json>& tile_results,
                                  const std::string& job_dir) = 0;
};

}  // namespace satmesh::server
