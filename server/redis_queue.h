#pragma once
// The distributed queue on Redis Streams (issue 22). API nodes (satmesh-server --queue)
// put each tile of a job on one stream; satmesh-worker processes read it through one
// consumer group, refine the tiles into the shared data directory and record the results.
// Job and tile state live in Redis, so any API node answers for any job.
//
// Keys (PREFIX = RedisQueueOptions::prefix):
//   PREFIX:tiles                 stream, one entry per tile to run {job, tile}; group "workers"
//                                (acknowledged entries are trimmed: it holds queued and running tiles)
//   PREFIX:jobs                  sorted set of job ids by creation time (ms)
//   PREFIX:job:ID                hash: request, status, created, started, finished, updated,
//                                message, idempotency_key, pixels, tiles (JSON [[x, y], ...]),
//                                left (tiles without a result), assembled
//   PREFIX:job:ID:results        hash: tile -> its result record (HSETNX: the first wins, so
//                                a tile refined twice leaves one result)
//   PREFIX:job:ID:live           hash: tile -> {"progress", "worker"} while it runs
//   PREFIX:job:ID:attempts       hash: tile -> deliveries so far
//   PREFIX:idempotency:KEY       the job id submitted with that Idempotency-Key
//   PREFIX:workers               sorted set: consumer -> last seen (ms)
//   PREFIX:stats                 hash: tiles_done, tiles_failed, duration_sum_s
// Delivery is at least once: a worker writes the tile's files (atomically), records the
// result, assembles when it finished the job's last tile, then acknowledges (XACK). A
// worker that dies leaves its entry pending; after idle_timeout_s another worker claims
// it (XAUTOCLAIM) and either finds the result (acknowledges, assembles if that is what
// was left) or runs the tile again; after max_deliveries the tile is failed with the
// reason (dead letter) and the job's other tiles go on. The job's status moves to its
// end once, by a script (atomic in Redis), so it is assembled once.
#include <memory>
#include <mutex>
#include <string>

#include "server/job_queue.h"
#include "server/redis_client.h"

namespace satmesh::server {

struct RedisQueueOptions {
  std::string url;                 // redis://HOST[:PORT][/DB]
  std::string prefix = "satmesh";  // key prefix, non-empty (deployments sharing a Redis)
  double idle_timeout_s = 30;      // a running tile's entry untouched this long is reclaimed
                                   // (running workers touch theirs every third of it), s
  int max_deliveries = 3;          // deliveries of a tile before it fails (dead letter)
  // (ranges and help of both: RedisWorkerOptionTable(), redis_worker.h)
  std::string Check() const;
};

// An API node's view of the queue (no tile runs here). Thread-safe.
class RedisJobQueue : public JobQueue {
 public:
  RedisJobQueue(const RedisQueueOptions& options, std::string data_dir);
  void Start() override;  // creates the stream and its group when missing
  void Stop() override {}
  JobRecord Submit(const nlohmann::json& request, const JobSpec& spec, const ExecutionPlan& plan,
                   const std::string& idempotency_key, bool* created) override;
  std::optional<JobRecord> Get(const std::string& id) const override;
  std::vector<JobRecord> List(std::optional<JobStatus> status, size_t limit) const override;
  std::optional<JobRecord> Dismiss(const std::string& id) override;
  // Polls: returns version + 1 after min(timeout, 500 ms) (progress comes from other
  // machines, read again by the caller).
  uint64_t WaitForChange(uint64_t version, int timeout_ms) const override;
  uint64_t version() const override { return 0; }
  SchedulerStats Stats() const override;
  std::string JobDir(const std::string& id) const override { return store_.JobDir(id); }

 private:
  RedisQueueOptions options_;
  JobStore store_;
  mutable std::mutex mu_;  // one connection, one command at a time
  std::unique_ptr<RedisConnection> redis_;
};

}  // namespace satmesh::server
