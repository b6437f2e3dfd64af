#include "server/scheduler.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <random>
#include <thread>

#include "core/common/error.h"
#include "core/common/threads.h"
#include "proto/job_spec_json.h"

namespace satmesh::server {
namespace {

// constexpr (no destructor): a worker still finishing a tile while the process exits must
// not read a destroyed vector (ASan, fuzz_http).
constexpr std::array<double, 12> kDurationBuckets = {0.1, 0.5, 1, 2, 5, 10, 30, 60, 120, 300, 600, 1800};

// Every tile finished: done or failed (the failure policy of core/tiling/job.h).
bool AllFinished(const JobRecord& r) {
  return std::all_of(r.tiles.begin(), r.tiles.end(), [](const TileRecord& t) {
    return t.status == TileStatus::kDone || t.status == TileStatus::kFailed;
  });
}

}  // namespace

std::string NewJobId() {
  std::random_device rd;
  std::mt19937_64 gen((uint64_t(rd()) << 32) ^ rd());
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(gen()));
  return buf;
}

std::string NoTileDoneMessage(const JobRecord& r) {
  for (const TileRecord& t : r.tiles)
    if (t.status == TileStatus::kDone) return "";
  if (r.tiles.empty()) return "the job has no tile";
  const TileRecord& first = r.tiles.front();
  return (r.tiles.size() == 1 ? "tile " : "every tile failed; first: tile ") + first.key.Name() + ": " +
         first.message;
}

std::string DoneMessage(const JobRecord& r) {
  const auto failed = std::count_if(r.tiles.begin(), r.tiles.end(),
                                    [](const TileRecord& t) { return t.status == TileStatus::kFailed; });
  for (const TileRecord& t : r.tiles)
    if (t.status == TileStatus::kFailed)
      return "done; " + std::to_string(failed) + " of " + std::to_string(r.tiles.size()) +
             " tiles failed; first: tile " + t.key.Name() + ": " + t.message;
  return "done";
}

std::string SchedulerOptions::Check() const {
  if (workers < 1 || workers > 256) return "workers: " + std::to_string(workers) + " not in [1, 256]";
  if (!(no_space_retry_s > 0 && no_space_retry_s <= 3600))
    return "no_space_retry_s: " + std::to_string(no_space_retry_s) + " not in (0, 3600]";
  return "";
}

Scheduler::Scheduler(JobStore* store, JobExecutor* executor, const SchedulerOptions& options)
    : store_(store), executor_(executor), options_(options),
      duration_counts_(kDurationBuckets.size() + 1, 0) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "scheduler options: " + problem);
}

Scheduler::~Scheduler() { Stop(); }

void Scheduler::Start() {
  std::vector<std::string> resumed;
  for (JobRecord& record : store_->LoadAll()) {
    Entry entry;
    if (!IsTerminal(record.status)) {
      for (auto& t : record.tiles)
        if (t.status == TileStatus::kRunning) t.status = TileStatus::kQueued;
      try {
        entry.spec = proto::JobSpecFromJson(record.request, "/");
      } catch (const std::exception& e) {
        record.status = JobStatus::kFailed;
        record.message = std::string("cannot resume: ") + e.what();
      }
    }
    const std::string id = record.id;
    entry.record = std::move(record);
    const bool resume = !IsTerminal(entry.record.status);
    {
      std::lock_guard lock(mu_);
      jobs_[id] = std::move(entry);
      if (resume) ready_.push_back(id);
    }
    if (resume) resumed.push_back(id);
    Persist(id);
  }
  if (!resumed.empty()) spdlog::info("resuming {} unfinished job(s)", resumed.size());
  stopping_ = false;
  for (int i = 0; i < options_.workers; ++i) workers_.emplace_back([this] { WorkerLoop(); });
}

void Scheduler::Stop() {
  {
    std::lock_guard lock(mu_);
    stopping_ = true;
  }
  work_cv_.notify_all();
  change_cv_.notify_all();
  for (auto& w : workers_) w.join();
  workers_.clear();
}

JobRecord Scheduler::Submit(const nlohmann::json& request, const JobSpec& spec,
                            const ExecutionPlan& plan, const std::string& idempotency_key,
                            bool* created) {
  Entry entry;
  {
    std::lock_guard lock(mu_);
    if (!idempotency_key.empty()) {
      for (const auto& [id, e] : jobs_) {
        if (e.record.idempotency_key == idempotency_key) {
          *created = false;
          return e.record;
        }
      }
    }
  }
  JobRecord& r = entry.record;
  r.id = NewJobId();
  r.idempotency_key = idempotency_key;
  r.request = request;
  r.created = r.updated = NowRfc3339();
  r.pixels = plan.pixels;
  for (const TileKey& key : plan.tiles) {
    TileRecord tile;
    tile.key = key;
    r.tiles.push_back(tile);
  }
  entry.spec = spec;
  store_->SaveRequest(r);
  store_->SaveState(r);
  const JobRecord copy = r;
  {
    std::lock_guard lock(mu_);
    jobs_[r.id] = std::move(entry);
    ready_.push_back(copy.id);
    ++version_;
  }
  work_cv_.notify_all();
  change_cv_.notify_all();
  *created = true;
  return copy;
}

std::optional<JobRecord> Scheduler::Get(const std::string& id) const {
  std::lock_guard lock(mu_);
  const auto it = jobs_.find(id);
  if (it == jobs_.end()) return std::nullopt;
  return it->second.record;
}

std::vector<JobRecord> Scheduler::List(std::optional<JobStatus> status, size_t limit) const {
  std::vector<JobRecord> out;
  {
    std::lock_guard lock(mu_);
    for (const auto& [id, e] : jobs_)
      if (!status || e.record.status == *status) out.push_back(e.record);
  }
  std::sort(out.begin(), out.end(), [](const JobRecord& a, const JobRecord& b) {
    return a.created != b.created ? a.created > b.created : a.id < b.id;
  });
  if (out.size() > limit) out.resize(limit);
  return out;
}

std::optional<JobRecord> Scheduler::Dismiss(const std::string& id) {
  bool remove_now = false;
  JobRecord copy;
  {
    std::lock_guard lock(mu_);
    const auto it = jobs_.find(id);
    if (it == jobs_.end()) return std::nullopt;
    Entry& e = it->second;
    e.cancel->store(true);
    if (e.record.status != JobStatus::kDismissed) {
      for (auto& t : e.record.tiles)
        if (t.status == TileStatus::kQueued) t.status = TileStatus::kCancelled;
      e.record.status = JobStatus::kDismissed;
      e.record.finished = NowRfc3339();
      e.record.message = "dismissed by the client";
      Touch(&e);
    }
    remove_now = e.running == 0 && !e.assembling;
    copy = e.record;
  }
  Persist(id);
  if (remove_now) store_->RemoveOutputs(id);
  change_cv_.notify_all();
  return copy;
}

uint64_t Scheduler::WaitForChange(uint64_t version, int timeout_ms) const {
  std::unique_lock lock(mu_);
  change_cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                      [&] { return version_ != version || stopping_; });
  return version_;
}

uint64_t Scheduler::version() const {
  std::lock_guard lock(mu_);
  return version_;
}

SchedulerStats Scheduler::Stats() const {
  SchedulerStats s;
  std::lock_guard lock(mu_);
  for (const auto& [id, e] : jobs_) {
    ++s.jobs_by_status[JobStatusName(e.record.status)];
    for (const auto& t : e.record.tiles) {
      s.tiles_queued += t.status == TileStatus::kQueued && !IsTerminal(e.record.status);
      s.tiles_running += t.status == TileStatus::kRunning;
    }
  }
  s.tiles_done = tiles_done_;
  s.tiles_failed = tiles_failed_;
  s.duration_buckets_s.assign(kDurationBuckets.begin(), kDurationBuckets.end());
  s.duration_counts = duration_counts_;
  s.duration_sum_s = duration_sum_s_;
  return s;
}

void Scheduler::Touch(Entry* e) {
  e->record.updated = NowRfc3339();
  ++version_;
}

void Scheduler::Persist(const std::string& id) {
  std::lock_guard save(save_mu_);
  JobRecord snapshot;
  {
    std::lock_guard lock(mu_);
    const auto it = jobs_.find(id);
    if (it == jobs_.end()) return;
    snapshot = it->second.record;
  }
  try {
    store_->SaveState(snapshot);
  } catch (const std::exception& e) {
    spdlog::error("job {}: cannot save state: {}", id, e.what());
  }
}

void Scheduler::WorkerLoop() {
  ShareProcessorsAmongWorkers(options_.workers);  // the tiles' loops split the cores
  while (true) {
    std::string id;
    size_t tile_index = SIZE_MAX;
    bool assemble = false;
    {
      std::unique_lock lock(mu_);
      work_cv_.wait(lock, [&] { return stopping_ || !ready_.empty(); });
      if (stopping_) return;
      id = ready_.front();
      ready_.pop_front();
      Entry& e = jobs_.at(id);
      if (IsTerminal(e.record.status)) continue;
      auto& tiles = e.record.tiles;
      for (size_t i = 0; i < tiles.size() && tile_index == SIZE_MAX; ++i)
        if (tiles[i].status == TileStatus::kQueued) tile_index = i;
      if (tile_index != SIZE_MAX) {
        TileRecord& t = tiles[tile_index];
        t.status = TileStatus::kRunning;
        t.progress = 0;
        ++t.attempts;
        ++e.running;
        if (e.record.status == JobStatus::kAccepted) {
          e.record.status = JobStatus::kRunning;
          e.record.started = NowRfc3339();
        }
        Touch(&e);
        const bool more = std::any_of(tiles.begin(), tiles.end(),
                                      [](const TileRecord& x) { return x.status == TileStatus::kQueued; });
        if (more) ready_.push_back(id);  // round robin: back of the line
      } else if (AllFinished(e.record) && !e.record.assembled && e.running == 0 && !e.assembling) {
        const std::string none_done = NoTileDoneMessage(e.record);
        if (none_done.empty()) {
          e.assembling = true;
          assemble = true;
        } else {  // nothing to assemble: the job fails
          e.record.status = JobStatus::kFailed;
          e.record.finished = NowRfc3339();
          e.record.message = none_done;
          Touch(&e);
        }
      } else {
        continue;
      }
    }
    work_cv_.notify_one();
    change_cv_.notify_all();
    Persist(id);
    if (assemble) AssembleJob(id);
    else if (tile_index != SIZE_MAX) RunOneTile(id, tile_index);  // else: failed, nothing to run
  }
}

void Scheduler::RunOneTile(const std::string& id, size_t tile_index) {
  JobSpec spec;
  TileKey key;
  std::shared_ptr<std::atomic<bool>> cancel;
  {
    std::lock_guard lock(mu_);
    Entry& e = jobs_.at(id);
    spec = e.spec;
    key = e.record.tiles[tile_index].key;
    cancel = e.cancel;
  }
  Progress progress;
  progress.is_cancelled = [this, cancel] { return cancel->load() || stopping_.load(); };
  progress.on_progress = [this, id, tile_index](double fraction, const std::string&) {
    {
      std::lock_guard lock(mu_);
      jobs_.at(id).record.tiles[tile_index].progress = std::clamp(fraction, 0.0, 1.0);
      ++version_;
    }
    change_cv_.notify_all();
  };
  enum { kDone, kFailed, kCancelled, kNoSpace } outcome = kDone;
  std::string message;
  nlohmann::json result;
  const auto t0 = std::chrono::steady_clock::now();
  // The engine returns a failed tile as a record; an exception other than cancellation is
  // that tile's failure too (the same policy).
  std::string code;
  try {
    result = executor_->RunTile(spec, key, store_->JobDir(id), progress);
  } catch (const Error& err) {
    outcome = err.code() == ErrorCode::kCancelled ? kCancelled : kFailed;
    code = ErrorCodeName(err.code());
    message = err.what();
  } catch (const std::exception& err) {
    outcome = kFailed;
    code = ErrorCodeName(ErrorCode::kInternal);
    message = err.what();
  }
  if (outcome == kDone && TileRecordFailed(result, &code, &message)) outcome = kFailed;
  if (outcome == kFailed && code == ErrorCodeName(ErrorCode::kNoSpace)) outcome = kNoSpace;
  if (outcome == kFailed && !result.is_object()) result = FailedTileRecord(key, code, message);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  bool remove_outputs = false, more_work = false, retry_later = false;
  // A finished tile is written to disk before anyone can see it done, so a tile reported
  // done is never run again after a crash (save_mu_ held until memory matches the disk).
  std::unique_lock save(save_mu_, std::defer_lock);
  if (outcome == kDone || outcome == kFailed) {
    save.lock();
    JobRecord snapshot;
    {
      std::lock_guard lock(mu_);
      snapshot = jobs_.at(id).record;
    }
    if (snapshot.status != JobStatus::kDismissed) {
      TileRecord& t = snapshot.tiles[tile_index];
      t.status = outcome == kDone ? TileStatus::kDone : TileStatus::kFailed;
      t.message = outcome == kDone ? "" : message;
      t.duration_s = seconds;
      t.result = result;
      snapshot.updated = NowRfc3339();
      try {
        store_->SaveState(snapshot);
      } catch (const std::exception& err) {
        spdlog::error("job {}: cannot save state: {}", id, err.what());
      }
    }
  }
  {
    std::lock_guard lock(mu_);
    Entry& e = jobs_.at(id);
    TileRecord& t = e.record.tiles[tile_index];
    --e.running;
    if (outcome == kDone && e.record.status != JobStatus::kDismissed) {
      t.status = TileStatus::kDone;
      t.message.clear();
      if (e.record.message.rfind("waiting for disk space", 0) == 0) e.record.message.clear();
      t.progress = 1;
      t.duration_s = seconds;
      t.result = std::move(result);
      ++tiles_done_;
      duration_sum_s_ += seconds;
      for (size_t b = 0; b < duration_counts_.size(); ++b)
        if (b == kDurationBuckets.size() || seconds <= kDurationBuckets[b]) ++duration_counts_[b];
      more_work = AllFinished(e.record);
    } else if (outcome == kFailed && e.record.status != JobStatus::kDismissed) {
      // That tile fails; the job's other tiles go on (core/tiling/job.h).
      t.status = TileStatus::kFailed;
      t.message = message;
      t.progress = 0;
      t.duration_s = seconds;
      t.result = std::move(result);
      ++tiles_failed_;
      more_work = AllFinished(e.record);
    } else if (outcome == kNoSpace && e.record.status != JobStatus::kDismissed) {
      // A full disk is not the tile's fault: back to the queue, retried after a pause.
      t.status = TileStatus::kQueued;
      t.progress = 0;
      t.message = message;
      e.record.message = "waiting for disk space: tile " + key.Name() + ": " + message;
      retry_later = true;
    } else if (e.record.status == JobStatus::kDismissed || outcome == kDone) {
      t.status = TileStatus::kCancelled;
    } else {
      t.status = TileStatus::kQueued;  // server stopping: resume on the next start
    }
    if (outcome == kFailed) spdlog::warn("job {} tile {} failed: {}", id, key.Name(), message);
    if (retry_later)
      spdlog::warn("job {} tile {}: {}; retried in {} s", id, key.Name(), message, options_.no_space_retry_s);
    remove_outputs = e.record.status == JobStatus::kDismissed && e.running == 0;
    if (more_work) ready_.push_back(id);
    Touch(&e);
  }
  if (save.owns_lock()) save.unlock();
  Persist(id);
  if (remove_outputs) store_->RemoveOutputs(id);
  if (more_work) work_cv_.notify_one();
  change_cv_.notify_all();
  if (retry_later) RetryAfterPause(id);
}

void Scheduler::RetryAfterPause(const std::string& id) {
  // In short sleeps (not on work_cv_, whose single wake-ups belong to idle workers), so a
  // stopping server does not wait for the pause.
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(options_.no_space_retry_s);
  while (!stopping_ && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  {
    std::lock_guard lock(mu_);
    if (stopping_ || std::find(ready_.begin(), ready_.end(), id) != ready_.end()) return;
    ready_.push_back(id);
  }
  work_cv_.notify_one();
}

void Scheduler::AssembleJob(const std::string& id) {
  JobSpec spec;
  std::vector<TileKey> keys;
  std::vector<nlohmann::json> results;
  {
    std::lock_guard lock(mu_);
    Entry& e = jobs_.at(id);
    spec = e.spec;
    for (const auto& t : e.record.tiles) {
      keys.push_back(t.key);
      results.push_back(t.result);
    }
  }
  std::string message;
  bool no_space = false;
  try {
    executor_->Assemble(spec, keys, results, store_->JobDir(id));
  } catch (const Error& err) {
    no_space = err.code() == ErrorCode::kNoSpace;
    message = std::string("assembling the outputs: ") + err.what();
  } catch (const std::exception& err) {
    message = std::string("assembling the outputs: ") + err.what();
  }
  bool remove_outputs = false;
  {
    std::lock_guard lock(mu_);
    Entry& e = jobs_.at(id);
    e.assembling = false;
    if (no_space && e.record.status != JobStatus::kDismissed) {
      e.record.message = "waiting for disk space: " + message;  // assembled again after a pause
    } else if (e.record.status != JobStatus::kDismissed) {
      e.record.assembled = message.empty();
      e.record.status = message.empty() ? JobStatus::kSuccessful : JobStatus::kFailed;
      e.record.message = message.empty() ? DoneMessage(e.record) : message;
      e.record.finished = NowRfc3339();
    }
    remove_outputs = e.record.status == JobStatus::kDismissed;
    Touch(&e);
  }
  Persist(id);
  if (remove_outputs) store_->RemoveOutputs(id);
  change_cv_.notify_all();
  if (no_space) {
    spdlog::warn("job {}: {}; retried in {} s", id, message, options_.no_space_retry_s);
    RetryAfterPause(id);
  }
}

}  // namespace satmesh::server
