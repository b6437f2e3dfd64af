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

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  for (const auto& a : args)
    if (a == "--help" || a == "-h") {
      std::printf("%s", satmesh::server::RedisWorkerUsage().c_str());
      return 0;
    }
  try {
    const auto options = satmesh::server::ParseRedisWorkerArgs(args);
    // Signals blocked everywhere; this thread waits for one and stops the consumers (a
    // running tile is cancelled and stays pending, reclaimed by another worker).
    sigset_t signals;
    sigemptyset(&signals);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &signals, nullptr);
    std::atomic<bool> stop{false};
    // A tile over this worker's budget fails before it starts (never killed by the kernel).
    satmesh::server::RealExecutor executor(options.MemoryBudgetMb());
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
