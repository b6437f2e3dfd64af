#include "server/redis_worker.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <thread>

#include "core/common/error.h"
#include "core/common/threads.h"
#include "core/tiling/memory_budget.h"
#include "proto/job_spec_json.h"
#include "server/redis_jobs.h"

namespace satmesh::server {
namespace {

using nlohmann::json;

// Marks a job started (accepted -> running); returns its status (nil: no such job).
constexpr const char* kStartScript = R"(
local s = redis.call('HGET', KEYS[1], 'status')
if s == 'accepted' then
  redis.call('HSET', KEYS[1], 'status', 'running', 'started', ARGV[1], 'updated', ARGV[1])
  return 'running'
end
return s)";

// Records a tile's result once: -1 when it had one already, else the job's tiles left.
constexpr const char* kFinishTileScript = R"(
if redis.call('HSETNX', KEYS[2], ARGV[1], ARGV[2]) == 0 then return -1 end
redis.call('HDEL', KEYS[3], ARGV[1])
redis.call('HSET', KEYS[1], 'updated', ARGV[3])
if ARGV[4] == '1' then
  redis.call('HINCRBY', KEYS[4], 'tiles_failed', 1)
else
  redis.call('HINCRBY', KEYS[4], 'tiles_done', 1)
  redis.call('HINCRBYFLOAT', KEYS[4], 'duration_sum_s', ARGV[5])
end
return redis.call('HINCRBY', KEYS[1], 'left', -1))";

// Ends a running job once: 1 when this call ended it.
constexpr const char* kEndScript = R"(
if redis.call('HGET', KEYS[1], 'status') ~= 'running' then return 0 end
redis.call('HSET', KEYS[1], 'status', ARGV[1], 'message', ARGV[2], 'finished', ARGV[3],
           'updated', ARGV[3], 'assembled', ARGV[4])
return 1)";

// Acknowledges an entry and trims the stream: entries below the oldest pending one (or, with
// none pending, up to the group's last delivered one) are acknowledged and go (XTRIM
// MINID), so the stream holds only queued and running tiles. XTRIM, not XDEL: trimming
// leaves no tombstones, so the group's lag (the API nodes' queue depth) stays defined.
// Returns the stream's length after.
constexpr const char* kAckScript = R"(
redis.call('XACK', KEYS[1], ARGV[1], ARGV[2])
local pending = redis.call('XPENDING', KEYS[1], ARGV[1])
local min_id
if pending[1] > 0 then
  min_id = pending[2]
else
  for _, group in ipairs(redis.call('XINFO', 'GROUPS', KEYS[1])) do
    local g = {}
    for i = 1, #group, 2 do g[group[i]] = group[i + 1] end
    if g['name'] == ARGV[1] then
      local ms, seq = string.match(g['last-delivered-id'], '^(%d+)-(%d+)$')
      if ms then min_id = ms .. '-' .. (tonumber(seq) + 1) end
    end
  end
end
if min_id then redis.call('XTRIM', KEYS[1], 'MINID', min_id) end
return redis.call('XLEN', KEYS[1]))";

struct Entry {
  std::string id, job, tile;
};

std::vector<Entry> Entries(const RedisReply& list) {
  std::vector<Entry> out;
  for (const RedisReply& e : list.elements) {
    if (e.elements.size() < 2 || e.elements[1].nil()) continue;
    const auto fields = FieldMap(e.elements[1]);
    out.push_back({e.elements[0].str, Field(fields, "job"), Field(fields, "tile")});
  }
  return out;
}

// While a worker holds an entry (refining its tile, assembling its job): a thread of its
// own (own connection) keeps the entry claimed (XCLAIM JUSTID resets its idle time, every
// third of the idle timeout), polls the job's status for cancellation and publishes the
// tile's progress to the live hash.
class Heartbeat {
 public:
  Heartbeat(const RedisWorkerOptions& options, const RedisKeys& keys, std::string consumer, std::string entry_id,
            std::string job, std::string tile)
      : thread_([=, this] { Loop(options, keys, consumer, entry_id, job, tile); }) {}
  ~Heartbeat() {
    done_ = true;
    thread_.join();
  }
  bool cancelled() const { return cancelled_; }
  void Report(double fraction) { progress_ = std::clamp(fraction, 0.0, 1.0); }

 private:
  void Loop(const RedisWorkerOptions& options, const RedisKeys& keys, const std::string& consumer,
            const std::string& entry_id, const std::string& job, const std::string& tile) {
    RedisConnection redis(ParseRedisUrl(options.queue.url));
    auto last_touch = std::chrono::steady_clock::now();
    double published = 0;
    while (!done_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
      try {
        const RedisReply status = redis.Command({"HGET", keys.Job(job), "status"});
        if (status.nil() || status.str != "running") cancelled_ = true;
        if (progress_ != published && !cancelled_) {
          published = progress_;
          redis.Command({"HSET", keys.Live(job), tile, json{{"progress", published}, {"worker", consumer}}.dump()});
        }
        const auto now = std::chrono::steady_clock::now();
        if (now - last_touch > std::chrono::duration<double>(options.queue.idle_timeout_s / 3)) {
          last_touch = now;
          redis.Command({"XCLAIM", keys.Stream(), kRedisGroup, consumer, "0", entry_id, "JUSTID"});
        }
      } catch (const std::exception& err) {
        spdlog::warn("{}: heartbeat: {}", consumer, err.what());
      }
    }
  }
  std::atomic<bool> done_{false}, cancelled_{false};
  std::atomic<double> progress_{0};
  std::thread thread_;  // last: starts after the flags exist
};

class Consumer {
 public:
  Consumer(const RedisWorkerOptions& options, JobExecutor* executor, std::string name,
           const std::atomic<bool>& stop)
      : options_(options), executor_(executor), name_(std::move(name)), stop_(stop),
        keys_{options.queue.prefix}, store_(options.data_dir),
        redis_(ParseRedisUrl(options.queue.url)) {}

  void Run() {
    ShareProcessorsAmongWorkers(options_.threads);
    auto last_claim = std::chrono::steady_clock::now() - std::chrono::hours(1);
    while (!stop_) {
      try {
        EnsureGroup(redis_, keys_);
        redis_.Command({"ZADD", keys_.Workers(), std::to_string(NowMs()), name_});
        std::vector<Entry> entries;
        // Tiles of dead or hung workers first, every few seconds.
        const auto now = std::chrono::steady_clock::now();
        if (now - last_claim > std::chrono::duration<double>(std::min(2.0, options_.queue.idle_timeout_s / 2))) {
          last_claim = now;
          const RedisReply claimed = redis_.Command(
              {"XAUTOCLAIM", keys_.Stream(), kRedisGroup, name_, IdleMs(), "0-0", "COUNT", "1"});
          if (claimed.elements.size() >= 2) entries = Entries(claimed.elements[1]);
          for (const Entry& e : entries) spdlog::info("{}: reclaimed tile {} of job {}", name_, e.tile, e.job);
        }
        if (entries.empty()) {
          const RedisReply read = redis_.Command({"XREADGROUP", "GROUP", kRedisGroup, name_, "COUNT", "1", "BLOCK",
                                                  "1000", "STREAMS", keys_.Stream(), ">"});
          if (!read.nil() && !read.elements.empty() && read.elements[0].elements.size() >= 2)
            entries = Entries(read.elements[0].elements[1]);
        }
        for (const Entry& e : entries) Handle(e);
      } catch (const std::exception& e) {
        spdlog::warn("{}: {}; retrying in 1 s", name_, e.what());
        std::this_thread::sleep_for(std::chrono::seconds(1));
      }
    }
  }

 private:
  std::string IdleMs() const { return std::to_string(int64_t(options_.queue.idle_timeout_s * 1000)); }

  void Ack(const Entry& e) { redis_.Command({"EVAL", kAckScript, "1", keys_.Stream(), kRedisGroup, e.id}); }

  void Handle(const Entry& e) {
    const RedisReply status = redis_.Command({"EVAL", kStartScript, "1", keys_.Job(e.job), NowRfc3339()});
    if (status.nil() || status.str != "running") {  // gone, dismissed or ended: nothing to do
      Ack(e);
      return;
    }
    if (redis_.Command({"HEXISTS", keys_.Results(e.job), e.tile}).integer == 1) {
      // Refined already (its worker died before acknowledging): one result stays; the job
      // is assembled here if that worker died before doing it.
      if (redis_.Command({"HGET", keys_.Job(e.job), "left"}).str == "0") {
        const Heartbeat heartbeat(options_, keys_, name_, e.id, e.job, e.tile);
        Assemble(e.job);
      }
      Ack(e);
      return;
    }
    const long long attempts = redis_.Command({"HINCRBY", keys_.Attempts(e.job), e.tile, "1"}).integer;
    const auto loaded = LoadJob(redis_, keys_, e.job);
    if (!loaded) {
      Ack(e);
      return;
    }
    const JobRecord& job = *loaded;
    TileKey key;
    for (const TileRecord& t : job.tiles)
      if (t.key.Name() == e.tile) key = t.key;
    if (attempts > options_.queue.max_deliveries) {  // dead letter
      const std::string why = "dead letter: delivered " + std::to_string(attempts - 1) +
                              " times without a result (its workers died or hung)";
      spdlog::warn("{}: job {} tile {}: {}", name_, e.job, e.tile, why);
      Finish(e, FailedTileRecord(key, ErrorCodeName(ErrorCode::kInternal), why), /*failed=*/true, 0);
      return;
    }
    redis_.Command({"HSET", keys_.Live(e.job), e.tile, json{{"progress", 0}, {"worker", name_}}.dump()});
    Run(e, job, key);
  }

  // Refines the tile under a Heartbeat.
  void Run(const Entry& e, const JobRecord& job, const TileKey& key) {
    std::optional<Heartbeat> heartbeat;
    heartbeat.emplace(options_, keys_, name_, e.id, e.job, e.tile);
    Progress progress;
    progress.is_cancelled = [&] { return heartbeat->cancelled() || stop_.load(); };
    progress.on_progress = [&](double fraction, const std::string&) { heartbeat->Report(fraction); };
    const auto t0 = std::chrono::steady_clock::now();
    json record;
    bool was_cancelled = false;
    try {
      const JobSpec spec = proto::JobSpecFromJson(job.request, "/");
      record = executor_->RunTile(spec, key, store_.JobDir(job.id), progress);
    } catch (const Error& err) {
      if (err.code() == ErrorCode::kCancelled) was_cancelled = true;
      else record = FailedTileRecord(key, ErrorCodeName(err.code()), err.what());
    } catch (const std::exception& err) {
      record = FailedTileRecord(key, ErrorCodeName(ErrorCode::kInternal), err.what());
    }
    heartbeat.reset();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (was_cancelled) {
      redis_.Command({"HDEL", keys_.Live(e.job), e.tile});
      if (stop_) return;  // this worker stops: the entry stays pending for another one
      spdlog::info("{}: job {} tile {} cancelled", name_, e.job, e.tile);
      const RedisReply st = redis_.Command({"HGET", keys_.Job(e.job), "status"});
      if (!st.nil() && st.str == "dismissed") store_.RemoveOutputs(e.job);
      Ack(e);
      return;
    }
    std::string code, message;
    const bool failed = TileRecordFailed(record, &code, &message);
    if (failed && code == ErrorCodeName(ErrorCode::kNoSpace)) {
      // Not the tile's fault: left pending, reclaimed (and retried) after the idle timeout.
      spdlog::warn("{}: job {} tile {}: {}; left for a retry", name_, e.job, e.tile, message);
      redis_.Command({"HDEL", keys_.Live(e.job), e.tile});
      return;
    }
    record["duration_s"] = seconds;
    Finish(e, record, failed, seconds);
  }

  // Records the result (once), assembles when it was the job's last tile, acknowledges.
  void Finish(const Entry& e, const json& record, bool failed, double seconds) {
    const RedisReply left = redis_.Command({"EVAL", kFinishTileScript, "4", keys_.Job(e.job), keys_.Results(e.job),
                                            keys_.Live(e.job), keys_.Stats(), e.tile, record.dump(), NowRfc3339(),
                                            failed ? "1" : "0", std::to_string(seconds)});
    spdlog::info("{}: job {} tile {} {}", name_, e.job, e.tile,
                 left.integer < 0 ? "had a result already" : failed ? "FAILED" : "done");
    if (left.integer == 0) {
      const Heartbeat heartbeat(options_, keys_, name_, e.id, e.job, e.tile);  // the entry stays ours
      Assemble(e.job);
    }
    Ack(e);
  }

  // Every tile has its result: the job ends here, once (kEndScript).
  void Assemble(const std::string& id) {
    const auto job = LoadJob(redis_, keys_, id);
    if (!job || job->status != JobStatus::kRunning) return;
    std::string message = NoTileDoneMessage(*job);
    bool ok = message.empty();
    if (ok) {
      std::vector<TileKey> keys;
      std::vector<json> results;
      for (const TileRecord& t : job->tiles) keys.push_back(t.key), results.push_back(t.result);
      try {
        executor_->Assemble(proto::JobSpecFromJson(job->request, "/"), keys, results, store_.JobDir(id));
        message = DoneMessage(*job);
      } catch (const std::exception& err) {
        ok = false;
        message = std::string("assembling the outputs: ") + err.what();
      }
    }
    const RedisReply ended = redis_.Command({"EVAL", kEndScript, "1", keys_.Job(id), ok ? "successful" : "failed",
                                             message, NowRfc3339(), ok ? "1" : "0"});
    if (ended.integer == 1) spdlog::info("{}: job {} {}: {}", name_, id, ok ? "successful" : "failed", message);
  }

  const RedisWorkerOptions& options_;
  JobExecutor* executor_;
  std::string name_;
  const std::atomic<bool>& stop_;
  RedisKeys keys_;
  JobStore store_;
  RedisConnection redis_;
};

}  // namespace

const std::vector<RedisWorkerOptionInfo>& RedisWorkerOptionTable() {
  using Range = OptionRange;
  using W = RedisWorkerOptions;
  using Q = RedisQueueOptions;
  static const std::vector<RedisWorkerOptionInfo> table = {
      {"threads", &W::threads, Range::In(1, 256), "tiles refined at once"},
      {"memory-budget", &W::memory_budget_mb, Range::AtLeast(0),
       "one thread's memory budget, MB; 0: a quarter of the machine's memory / threads. A tile "
       "estimated over it fails unstarted, naming budget and need"},
      {"idle-timeout-s", &Q::idle_timeout_s, Range::In(0.5, 86400),
       "a running tile's entry untouched this long is claimed by another worker, s"},
      {"max-deliveries", &Q::max_deliveries, Range::AtLeast(1),
       "deliveries of a tile before it fails (dead letter)"},
  };
  return table;
}

std::string RedisWorkerOptions::Check() const {
  const std::string q = queue.Check();
  if (!q.empty()) return q;
  if (data_dir.empty()) return "data_dir: required";
  const std::string problem = CheckOptionRanges(RedisWorkerOptionTable(), *this);
  return problem.empty() ? "" : "--" + problem;
}

double RedisWorkerOptions::MemoryBudgetMb() const {
  return memory_budget_mb > 0 ? memory_budget_mb : DefaultMemoryBudgetMb(threads);
}

std::string RedisWorkerUsage() {
  std::string out =
      "usage: satmesh-worker --queue redis://HOST:PORT[/DB] --data-dir DIR [--prefix satmesh] [--name NAME]\n";
  for (const RedisWorkerOptionInfo& o : RedisWorkerOptionTable()) {
    const std::string flag = "[--" + std::string(o.name) + " " + OptionValueText(o.Default()) + "]";
    out += "  " + flag + std::string(flag.size() < 24 ? 24 - flag.size() : 1, ' ') + std::string(o.help) + " (" +
           o.RangeText() + ")\n";
  }
  return out;
}

RedisWorkerOptions ParseRedisWorkerArgs(const std::vector<std::string>& args) {
  RedisWorkerOptions o;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    SATMESH_CHECK(arg.rfind("--", 0) == 0 && i + 1 < args.size(), ErrorCode::kInvalidArgument,
                  "unexpected argument '" + arg + "'\n" + RedisWorkerUsage());
    const std::string key = arg.substr(2), value = args[++i];
    if (key == "queue") o.queue.url = value;
    else if (key == "data-dir") o.data_dir = value;
    else if (key == "prefix") o.queue.prefix = value;
    else if (key == "name") o.name = value;
    else if (const RedisWorkerOptionInfo* option = FindOption(RedisWorkerOptionTable(), key)) {
      size_t used = 0;
      double v = 0;
      try {
        v = std::stod(value, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      const bool integer = option->type() == OptionType::kInt;
      SATMESH_CHECK(used == value.size() && !value.empty() && (!integer || v == std::floor(v)),
                    ErrorCode::kInvalidArgument,
                    arg + ": expected " + (integer ? "an integer" : "a number") + ", got '" + value + "'");
      option->Set(&o, integer ? OptionValue(int(std::clamp(v, -1e9, 1e9))) : OptionValue(v));
    } else {
      ThrowError(ErrorCode::kInvalidArgument, "unknown option " + arg + "\n" + RedisWorkerUsage());
    }
  }
  const std::string problem = o.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, problem + "\n" + RedisWorkerUsage());
  ParseRedisUrl(o.queue.url);
  return o;
}

int RunRedisWorker(const RedisWorkerOptions& options, JobExecutor* executor, const std::atomic<bool>& stop) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "worker options: " + problem);
  std::string base = options.name;
  if (base.empty()) {
    char host[256] = {};
    ::gethostname(host, sizeof host - 1);
    base = std::string(host) + "-" + std::to_string(::getpid());
  }
  spdlog::info("satmesh-worker {}: {} thread(s) on {} (data: {}), memory budget {:.0f} MB per thread", base,
               options.threads, options.queue.url, options.data_dir, options.MemoryBudgetMb());
  std::vector<std::thread> threads;
  for (int i = 0; i < options.threads; ++i)
    threads.emplace_back([&, i] {
      Consumer consumer(options, executor, base + "-" + std::to_string(i), stop);
      consumer.Run();
    });
  for (auto& t : threads) t.join();
  return 0;
}

}  // namespace satmesh::server
