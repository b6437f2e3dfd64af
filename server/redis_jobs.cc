#include "server/redis_jobs.h"

#include <chrono>

#include "core/common/error.h"

namespace satmesh::server {

using nlohmann::json;

int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::map<std::string, std::string> FieldMap(const RedisReply& r) {
  std::map<std::string, std::string> out;
  for (size_t i = 0; i + 1 < r.elements.size(); i += 2) out[r.elements[i].str] = r.elements[i + 1].str;
  return out;
}

std::string Field(const std::map<std::string, std::string>& m, const std::string& key) {
  const auto it = m.find(key);
  return it == m.end() ? "" : it->second;
}

void EnsureGroup(RedisConnection& redis, const RedisKeys& keys) {
  try {
    redis.Command({"XGROUP", "CREATE", keys.Stream(), kRedisGroup, "0", "MKSTREAM"});
  } catch (const Error& e) {
    if (std::string(e.what()).find("BUSYGROUP") == std::string::npos) throw;
  }
}

std::optional<JobRecord> LoadJob(RedisConnection& redis, const RedisKeys& keys, const std::string& id) {
  const auto job = FieldMap(redis.Command({"HGETALL", keys.Job(id)}));
  if (job.empty() || !job.count("status")) return std::nullopt;
  const auto results = FieldMap(redis.Command({"HGETALL", keys.Results(id)}));
  const auto live = FieldMap(redis.Command({"HGETALL", keys.Live(id)}));
  const auto attempts = FieldMap(redis.Command({"HGETALL", keys.Attempts(id)}));
  JobRecord r;
  r.id = id;
  r.request = json::parse(Field(job, "request"));
  r.status = JobStatusFromName(Field(job, "status"));
  r.created = Field(job, "created");
  r.started = Field(job, "started");
  r.finished = Field(job, "finished");
  r.updated = Field(job, "updated");
  r.message = Field(job, "message");
  r.idempotency_key = Field(job, "idempotency_key");
  r.pixels = std::atoll(Field(job, "pixels").c_str());
  r.assembled = Field(job, "assembled") == "1";
  for (const auto& xy : json::parse(Field(job, "tiles"))) {
    TileRecord t;
    t.key = {xy.at(0).get<int>(), xy.at(1).get<int>()};
    const std::string name = t.key.Name();
    t.attempts = std::atoi(Field(attempts, name).c_str());
    if (results.count(name)) {
      t.result = json::parse(results.at(name));
      std::string code;
      t.status = TileRecordFailed(t.result, &code, &t.message) ? TileStatus::kFailed : TileStatus::kDone;
      t.duration_s = t.result.value("duration_s", 0.0);
      t.progress = t.status == TileStatus::kDone ? 1 : 0;
    } else if (live.count(name) && !IsTerminal(r.status)) {
      t.status = TileStatus::kRunning;
      t.progress = json::parse(live.at(name)).value("progress", 0.0);
    } else {
      t.status = IsTerminal(r.status) ? TileStatus::kCancelled : TileStatus::kQueued;
    }
    r.tiles.push_back(std::move(t));
  }
  return r;
}

}  // namespace satmesh::server
