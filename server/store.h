#pragma once
// The embedded job store: one folder per job under the data directory,
//   <data>/jobs/<id>/job.json    the accepted request (hrefs resolved, absolute)
//   <data>/jobs/<id>/state.json  status, timestamps, per-tile states (written atomically)
//   <data>/jobs/<id>/tiles/<x>_<y>.glb, tileset.json, metrics.json, ...
// A restarted server reloads every job; tiles that were running go back to the queue.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "server/executor.h"

namespace satmesh::server {

enum class JobStatus { kAccepted, kRunning, kSuccessful, kFailed, kDismissed };
enum class TileStatus { kQueued, kRunning, kDone, kFailed, kCancelled };

const char* JobStatusName(JobStatus s);     // OGC names: accepted, running, ...
const char* TileStatusName(TileStatus s);   // queued, running, done, failed, cancelled
bool IsTerminal(JobStatus s);
// Throws Error{kInvalidArgument} for an unknown name.
JobStatus JobStatusFromName(const std::string& name);

struct TileRecord {
  TileKey key;
  TileStatus status = TileStatus::kQueued;
  double progress = 0;       // [0, 1] while running (not persisted mid-tile)
  double duration_s = 0;     // wall time of the run that finished it
  int attempts = 0;          // runs started (a restart re-runs an unfinished tile)
  std::string message;       // failure reason
  nlohmann::json result;     // what the executor returned for the tile (persisted)
};

struct JobRecord {
  std::string id;
  std::string idempotency_key;          // "" when none was given
  nlohmann::json request;               // job.json
  JobStatus status = JobStatus::kAccepted;
  std::string created, started, finished, updated;  // RFC 3339 UTC, "" when not yet
  std::string message;
  std::vector<TileRecord> tiles;
  bool assembled = false;               // tileset/metrics written
  int64_t pixels = 0;
};

std::string NowRfc3339();

class JobStore {
 public:
  explicit JobStore(std::string data_dir);  // creates <data>/jobs
  std::string JobDir(const std::string& id) const;
  // Writes job.json (once) and state.json (atomically: temp file + rename).
  void SaveRequest(const JobRecord& job) const;
  void SaveState(const JobRecord& job) const;
  // Every job found on disk; unreadable folders are skipped with a warning.
  std::vector<JobRecord> LoadAll() const;
  // Removes the outputs (tiles, results) of a dismissed job; keeps its state.
  void RemoveOutputs(const std::string& id) const;

 private:
  std::string jobs_dir_;
};

nlohmann::json StateToJson(const JobRecord& job);
JobRecord StateFromJson(const nlohmann::json& state);

}  // namespace satmesh::server
