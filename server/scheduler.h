#pragma once
// The worker pool: runs the tiles of all jobs, round-robin between jobs so one big job
// does not starve the others; cancellation reaches a running tile through its Progress.
// State changes are persisted through the JobStore (outside the lock readers take).
#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "server/executor.h"
#include "server/job_queue.h"
#include "server/store.h"

namespace satmesh::server {

struct SchedulerOptions {
  int workers = 2;  // tile worker threads, in [1, 256]
  // A tile (or the assembly) that fails for lack of disk space (Error{kNoSpace}) is not
  // failed: it goes back to the queue and its worker retries it after this long, so the
  // job resumes once space is back. Seconds, in (0, 3600].
  double no_space_retry_s = 10;
  std::string Check() const;
};

// The embedded queue (the default): jobs in this process, state in the JobStore.
class Scheduler : public JobQueue {
 public:
  Scheduler(JobStore* store, JobExecutor* executor, const SchedulerOptions& options);
  ~Scheduler() override;
  // Loads the store's jobs (unfinished tiles go back to the queue) and starts the workers.
  void Start() override;
  // Stops the workers; running tiles are cancelled and stay queued for the next start.
  void Stop() override;

  // Adds a validated, planned job. With a non-empty idempotency key already used, returns
  // that job instead and sets *created = false.
  JobRecord Submit(const nlohmann::json& request, const JobSpec& spec, const ExecutionPlan& plan,
                   const std::string& idempotency_key, bool* created) override;
  std::optional<JobRecord> Get(const std::string& id) const override;
  // Newest first; status filter optional; at most `limit`.
  std::vector<JobRecord> List(std::optional<JobStatus> status, size_t limit) const override;
  // Cancels the job's tiles and marks it dismissed; std::nullopt for an unknown id.
  std::optional<JobRecord> Dismiss(const std::string& id) override;
  // Blocks until the job changes after `version` or the timeout passes; returns the
  // current change counter (for progress streams).
  uint64_t WaitForChange(uint64_t version, int timeout_ms) const override;
  uint64_t version() const override;
  SchedulerStats Stats() const override;
  std::string JobDir(const std::string& id) const override { return store_->JobDir(id); }

 private:
  struct Entry {
    JobRecord record;
    JobSpec spec;
    std::shared_ptr<std::atomic<bool>> cancel = std::make_shared<std::atomic<bool>>(false);
    int running = 0;
    bool assembling = false;
  };
  void WorkerLoop();
  void RunOneTile(const std::string& id, size_t tile_index);
  void AssembleJob(const std::string& id);
  // After a kNoSpace failure: waits options_.no_space_retry_s, then queues the job again.
  void RetryAfterPause(const std::string& id);
  void Persist(const std::string& id);
  void Touch(Entry* e);  // updated timestamp + change counter (mu_ held)

  JobStore* store_;
  JobExecutor* executor_;
  SchedulerOptions options_;
  mutable std::mutex mu_;
  mutable std::condition_variable work_cv_, change_cv_;
  std::mutex save_mu_;  // serialises state writes so they land in order
  std::map<std::string, Entry> jobs_;
  std::deque<std::string> ready_;  // jobs with work, round robin
  std::vector<std::thread> workers_;
  std::atomic<bool> stopping_{false};
  uint64_t version_ = 0;
  int64_t tiles_done_ = 0, tiles_failed_ = 0;
  std::vector<int64_t> duration_counts_;
  double duration_sum_s_ = 0;
};

}  // namespace satmesh::server
