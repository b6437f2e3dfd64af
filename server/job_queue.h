#pragma once
// Where jobs wait and run, as the HTTP layer sees it: the embedded Scheduler (one process,
// the default) or the Redis queue (redis_queue.h: API nodes and satmesh-worker processes).
#include <nlohmann/json.hpp>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "server/executor.h"
#include "server/store.h"

namespace satmesh::server {

struct SchedulerStats {
  int tiles_queued = 0, tiles_running = 0;   // now
  int64_t tiles_done = 0, tiles_failed = 0;  // since start (Redis queue: since the queue's start)
  std::map<std::string, int> jobs_by_status;
  std::vector<double> duration_buckets_s;    // histogram upper bounds (+Inf implied)
  std::vector<int64_t> duration_counts;      // cumulative, one more than buckets (+Inf)
  double duration_sum_s = 0;
  int workers_seen = -1;                     // Redis queue: workers seen in the last minute; -1: n/a
};

// A new job's id: 16 random hex digits (the embedded scheduler and the Redis API nodes).
std::string NewJobId();

// The job's message once every tile finished (done or failed): "" when a tile is done
// (the job is assembled), else why it failed (every tile failed, the first named).
std::string NoTileDoneMessage(const JobRecord& job);
// The message of an assembled job: "done", or "done; N of M tiles failed; first: ...".
std::string DoneMessage(const JobRecord& job);

class JobQueue {
 public:
  virtual ~JobQueue() = default;
  // Starts the queue (the embedded one: loads the store, starts its workers).
  virtual void Start() = 0;
  // Stops it; running tiles stay queued for the next start (or another worker).
  virtual void Stop() = 0;
  // Adds a validated, planned job. With a non-empty idempotency key already used, returns
  // that job instead and sets *created = false.
  virtual JobRecord Submit(const nlohmann::json& request, const JobSpec& spec, const ExecutionPlan& plan,
                           const std::string& idempotency_key, bool* created) = 0;
  virtual std::optional<JobRecord> Get(const std::string& id) const = 0;
  // Newest first; status filter optional; at most `limit`.
  virtual std::vector<JobRecord> List(std::optional<JobStatus> status, size_t limit) const = 0;
  // Cancels the job's tiles and marks it dismissed; std::nullopt for an unknown id.
  virtual std::optional<JobRecord> Dismiss(const std::string& id) = 0;
  // Blocks until a job may have changed after `version` or the timeout passes; returns the
  // current change counter (for progress streams).
  virtual uint64_t WaitForChange(uint64_t version, int timeout_ms) const = 0;
  virtual uint64_t version() const = 0;
  virtual SchedulerStats Stats() const = 0;
  virtual std::string JobDir(const std::string& id) const = 0;
};

}  // namespace satmesh::server
