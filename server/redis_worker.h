#pragma once
// satmesh-worker's loop on the Redis queue (issue 22): consumers claim tiles from the
// stream (XREADGROUP, XAUTOCLAIM for dead workers' tiles), refine them into the shared data
// directory, record the results and acknowledge; the delivery rules are in redis_queue.h.
#include <atomic>
#include <string>

#include "server/executor.h"
#include "server/redis_queue.h"

namespace satmesh::server {

struct RedisWorkerOptions {
  RedisQueueOptions queue;
  std::string data_dir;   // the shared data directory (the API nodes' --data-dir)
  int threads = 1;        // tiles refined at once, [1, 256]
  std::string name;       // consumer name prefix; "" = host-pid
  std::string Check() const;
};

// Runs a worker until `stop` turns true: `threads` consumers claim tiles, refine them with
// `executor` and record them as redis_queue.h describes. Returns the process exit code.
int RunRedisWorker(const RedisWorkerOptions& options, JobExecutor* executor, const std::atomic<bool>& stop);

}  // namespace satmesh::server
