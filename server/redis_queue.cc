#include "server/redis_queue.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <random>
#include <thread>

#include "core/common/error.h"
#include "server/redis_jobs.h"
#include "server/redis_worker.h"

namespace satmesh::server {
namespace {

using nlohmann::json;




// Dismisses a job; returns its previous status (nil: no such job).
constexpr const char* kDismissScript = R"(
local s = redis.call('HGET', KEYS[1], 'status')
if not s then return nil end
if s ~= 'dismissed' then
  redis.call('HSET', KEYS[1], 'status', 'dismissed', 'finished', ARGV[1], 'updated', ARGV[1],
             'message', 'dismissed by the client')
end
return s)";







}  // namespace

std::string RedisQueueOptions::Check() const {
  if (url.empty()) return "queue: a redis://HOST[:PORT][/DB] URL is required";
  if (prefix.empty()) return "queue prefix: empty";
  // The numbers' ranges: the workers' option table (they are the workers' settings).
  RedisWorkerOptions worker;
  worker.queue = *this;
  const std::string problem = CheckOptionRanges(RedisWorkerOptionTable(), worker, /*nested_only=*/true);
  return problem.empty() ? "" : "--" + problem;
}


// ---- API node -------------------------------------------------------------------------

RedisJobQueue::RedisJobQueue(const RedisQueueOptions& options, std::string data_dir)
    : options_(options), store_(std::move(data_dir)) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, problem);
  redis_ = std::make_unique<RedisConnection>(ParseRedisUrl(options.url));
}

void RedisJobQueue::Start() {
  std::lock_guard lock(mu_);
  EnsureGroup(*redis_, RedisKeys{options_.prefix});
}

JobRecord RedisJobQueue::Submit(const json& request, const JobSpec&, const ExecutionPlan& plan,
                                const std::string& idempotency_key, bool* created) {
  const RedisKeys keys{options_.prefix};
  JobRecord r;
  r.id = NewJobId();
  std::lock_guard lock(mu_);
  if (!idempotency_key.empty()) {
    const RedisReply set = redis_->Command({"SET", keys.Idempotency(idempotency_key), r.id, "NX"});
    if (set.nil()) {
      const std::string existing = redis_->Command({"GET", keys.Idempotency(idempotency_key)}).str;
      if (auto job = LoadJob(*redis_, keys, existing)) {
        *created = false;
        return *job;
      }
    }
  }
  r.idempotency_key = idempotency_key;
  r.request = request;
  r.created = r.updated = NowRfc3339();
  r.pixels = plan.pixels;
  json tiles = json::array();
  for (const TileKey& key : plan.tiles) {
    TileRecord t;
    t.key = key;
    r.tiles.push_back(t);
    tiles.push_back({key.x, key.y});
  }
  store_.SaveRequest(r);  // job.json in the shared data directory (the job's folder)
  redis_->Command({"HSET", keys.Job(r.id), "request", request.dump(), "status", "accepted", "created", r.created,
                   "updated", r.updated, "message", "", "idempotency_key", idempotency_key, "pixels",
                   std::to_string(r.pixels), "tiles", tiles.dump(), "left", std::to_string(plan.tiles.size()),
                   "assembled", "0"});
  redis_->Command({"ZADD", keys.Jobs(), std::to_string(NowMs()), r.id});
  for (const TileKey& key : plan.tiles)
    redis_->Command({"XADD", keys.Stream(), "*", "job", r.id, "tile", key.Name()});
  *created = true;
  return r;
}

std::optional<JobRecord> RedisJobQueue::Get(const std::string& id) const {
  std::lock_guard lock(mu_);
  return LoadJob(*redis_, RedisKeys{options_.prefix}, id);
}

std::vector<JobRecord> RedisJobQueue::List(std::optional<JobStatus> status, size_t limit) const {
  const RedisKeys keys{options_.prefix};
  std::lock_guard lock(mu_);
  std::vector<JobRecord> out;
  for (const RedisReply& id : redis_->Command({"ZREVRANGE", keys.Jobs(), "0", "-1"}).elements) {
    if (out.size() >= limit) break;
    auto job = LoadJob(*redis_, keys, id.str);
    if (job && (!status || job->status == *status)) out.push_back(std::move(*job));
  }
  return out;
}

std::optional<JobRecord> RedisJobQueue::Dismiss(const std::string& id) {
  const RedisKeys keys{options_.prefix};
  {
    std::lock_guard lock(mu_);
    const RedisReply before = redis_->Command({"EVAL", kDismissScript, "1", keys.Job(id), NowRfc3339()});
    if (before.nil()) return std::nullopt;
  }
  // Running tiles see the status within a second (their workers poll it) and stop; the
  // outputs go now (a worker that stops also removes what it wrote since).
  store_.RemoveOutputs(id);
  return Get(id);
}

uint64_t RedisJobQueue::WaitForChange(uint64_t version, int timeout_ms) const {
  std::this_thread::sleep_for(std::chrono::milliseconds(std::clamp(timeout_ms, 0, 500)));
  return version + 1;
}

SchedulerStats RedisJobQueue::Stats() const {
  const RedisKeys keys{options_.prefix};
  SchedulerStats s;
  std::lock_guard lock(mu_);
  for (const RedisReply& group : redis_->Command({"XINFO", "GROUPS", keys.Stream()}).elements) {
    const auto fields = group.elements;
    std::string name;
    long long pending = 0, lag = 0;
    for (size_t i = 0; i + 1 < fields.size(); i += 2) {
      if (fields[i].str == "name") name = fields[i + 1].str;
      if (fields[i].str == "pending") pending = fields[i + 1].integer;
      if (fields[i].str == "lag") lag = fields[i + 1].integer;
    }
    if (name != kRedisGroup) continue;
    s.tiles_running = int(pending);
    s.tiles_queued = int(lag);
  }
  const auto stats = FieldMap(redis_->Command({"HGETALL", keys.Stats()}));
  s.tiles_done = std::atoll(Field(stats, "tiles_done").c_str());
  s.tiles_failed = std::atoll(Field(stats, "tiles_failed").c_str());
  s.duration_sum_s = std::atof(Field(stats, "duration_sum_s").c_str());
  s.duration_counts = {s.tiles_done};  // no buckets kept: +Inf only
  s.workers_seen = int(redis_->Command({"ZCOUNT", keys.Workers(), std::to_string(NowMs() - 60000), "+inf"}).integer);
  for (const RedisReply& id : redis_->Command({"ZRANGE", keys.Jobs(), "0", "-1"}).elements) {
    const RedisReply st = redis_->Command({"HGET", keys.Job(id.str), "status"});
    if (!st.nil()) ++s.jobs_by_status[st.str];
  }
  return s;
}

}  // namespace satmesh::server
