#pragma once
// satmesh-worker's loop on the Redis queue (issue 22): consumers claim tiles from the
// stream (XREADGROUP, XAUTOCLAIM for dead workers' tiles), refine them into the shared data
// directory, record the results and acknowledge; the delivery rules are in redis_queue.h.
#include <atomic>
#include <string>
#include <vector>

#include "core/common/option_table.h"
#include "server/executor.h"
#include "server/redis_queue.h"

namespace satmesh::server {

// satmesh-worker's options; the numbers' flags, ranges and help: RedisWorkerOptionTable().
struct RedisWorkerOptions {
  RedisQueueOptions queue;
  std::string data_dir;   // the shared data directory (the API nodes' --data-dir)
  int threads = 1;        // tiles refined at once
  double memory_budget_mb = 0;  // one thread's budget, MB; 0: DefaultMemoryBudgetMb(threads)
  std::string name;       // consumer name prefix; "" = host-pid
  std::string Check() const;
  double MemoryBudgetMb() const;  // memory_budget_mb, or the default for this machine
};

// The worker's numeric options, flags without "--" (core/common/option_table.h); the
// queue's idle_timeout_s and max_deliveries are the nested ones.
using RedisWorkerOptionInfo = OptionInfo<RedisWorkerOptions, RedisQueueOptions, &RedisWorkerOptions::queue>;
const std::vector<RedisWorkerOptionInfo>& RedisWorkerOptionTable();

// satmesh-worker's command line (without argv[0]): --queue URL --data-dir DIR [--prefix P]
// [--name N] and the table's options. Throws Error{kInvalidArgument} naming the problem.
RedisWorkerOptions ParseRedisWorkerArgs(const std::vector<std::string>& args);
std::string RedisWorkerUsage();

// Runs a worker until `stop` turns true: `threads` consumers claim tiles, refine them with
// `executor` and record them as redis_queue.h describes. Returns the process exit code.
int RunRedisWorker(const RedisWorkerOptions& options, JobExecutor* executor, const std::atomic<bool>& stop);

}  // namespace satmesh::server
