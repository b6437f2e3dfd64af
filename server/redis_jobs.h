#pragma once
// Job and tile state in Redis, as API nodes (redis_queue.h) and workers (redis_worker.h)
// both read and write it: the keys (listed in redis_queue.h), the consumer group and the
// job's record loaded from its hashes. Internal to server/.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "server/redis_client.h"
#include "server/store.h"

namespace satmesh::server {

constexpr const char* kRedisGroup = "workers";  // the stream's consumer group

struct RedisKeys {
  std::string prefix;
  std::string Stream() const { return prefix + ":tiles"; }
  std::string Jobs() const { return prefix + ":jobs"; }
  std::string Job(const std::string& id) const { return prefix + ":job:" + id; }
  std::string Results(const std::string& id) const { return Job(id) + ":results"; }
  std::string Live(const std::string& id) const { return Job(id) + ":live"; }
  std::string Attempts(const std::string& id) const { return Job(id) + ":attempts"; }
  std::string Idempotency(const std::string& key) const { return prefix + ":idempotency:" + key; }
  std::string Workers() const { return prefix + ":workers"; }
  std::string Stats() const { return prefix + ":stats"; }
};

// Wall-clock milliseconds since the epoch (sorted-set scores).
int64_t NowMs();
// A flat [field, value, ...] reply (HGETALL, a stream entry) as a map.
std::map<std::string, std::string> FieldMap(const RedisReply& r);
// m[key], "" when absent.
std::string Field(const std::map<std::string, std::string>& m, const std::string& key);
// Creates the stream and its consumer group when missing.
void EnsureGroup(RedisConnection& redis, const RedisKeys& keys);
// The job as the store's record, its tiles' states from results, live and attempts;
// nullopt when there is no such job.
std::optional<JobRecord> LoadJob(RedisConnection& redis, const RedisKeys& keys, const std::string& id);

}  // namespace satmesh::server
