// satmesh-worker: refines the tiles of the Redis queue's jobs (server/redis_worker.h, server/redis_queue.h) into
// the shared data directory. Same engine as satmesh-server's embedded workers.
#include <spdlog/spdlog.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <pthread.h>
#include <string>
#include <thread>
#include <vector>

#include "core/common/error.h"
#include "server/real_executor.h"
#include "server/redis_worker.h"

namespace {

std::string Usage() {
  return "usage: satmesh-worker --queue redis://HOST:PORT[/DB] --data-dir DIR [--threads 1]\n"
         "         [--idle-timeout-s 30] [--max-deliveries 3] [--prefix satmesh] [--name NAME]\n";
}

double Number(const std::string& key, const std::string& value) {
  try {
    size_t used = 0;
    const double v = std::stod(value, &used);
    if (used == value.size()) return v;
  } catch (const std::exception&) {
  }
  satmesh::ThrowError(satmesh::ErrorCode::kInvalidArgument, "--" + key + ": expected a number, got '" + value + "'");
}

satmesh::server::RedisWorkerOptions Parse(const std::vector<std::string>& args) {
  satmesh::server::RedisWorkerOptions o;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    SATMESH_CHECK(arg.rfind("--", 0) == 0 && i + 1 < args.size(), satmesh::ErrorCode::kInvalidArgument,
                  "unexpected argument '" + arg + "'\n" + Usage());
    const std::string key = arg.substr(2), value = args[++i];
    if (key == "queue") o.queue.url = value;
    else if (key == "data-dir") o.data_dir = value;
    else if (key == "threads") o.threads = int(Number(key, value));
    else if (key == "idle-timeout-s") o.queue.idle_timeout_s = Number(key, value);
    else if (key == "max-deliveries") o.queue.max_deliveries = int(Number(key, value));
    else if (key == "prefix") o.queue.prefix = value;
    else if (key == "name") o.name = value;
    else satmesh::ThrowError(satmesh::ErrorCode::kInvalidArgument, "unknown option --" + key + "\n" + Usage());
  }
  const std::string problem = o.Check();
  SATMESH_CHECK(problem.empty(), satmesh::ErrorCode::kInvalidArgument, problem + "\n" + Usage());
  satmesh::server::ParseRedisUrl(o.queue.url);
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args)
    if (a == "--help" || a == "-h") {
      std::printf("%s", Usage().c_str());
      return 0;
    }
  try {
    const auto options = Parse(args);
    // Signals blocked everywhere; this thread waits for one and stops the consumers (a
    // running tile is cancelled and stays pending, reclaimed by another worker).
    sigset_t signals;
    sigemptyset(&signals);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals, nullptr);
    std::atomic<bool> stop{false};
    satmesh::server::RealExecutor executor;
    int code = 0;
    std::thread run([&] { code = satmesh::server::RunRedisWorker(options, &executor, stop); });
    int received = 0;
    sigwait(&signals, &received);
    spdlog::info("signal {}: stopping", received);
    stop = true;
    run.join();
    return code;
  } catch (const satmesh::Error& e) {
    spdlog::error("{}", e.what());
    return e.code() == satmesh::ErrorCode::kInvalidArgument ? 2 : 1;
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
