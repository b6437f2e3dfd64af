#pragma once
// satmesh-server's HTTP API (OGC API - Processes style, RFC 7807 errors), bound to a
// JobExecutor through a JobQueue (the embedded Scheduler or Redis). Routes in api.cc, documents in api_documents.cc.
#include <memory>
#include <string>
#include <vector>

#include "server/executor.h"
#include "server/inputs.h"
#include "server/redis_queue.h"
#include "server/scheduler.h"

namespace satmesh::server {

struct ServerOptions {
  std::string host = "127.0.0.1";        // listen address
  int port = 8080;                       // TCP port, 0 = any free port
  std::string data_dir = "satmesh-data"; // job store root
  std::string proto_dir;                 // proto/ (schemas, OpenAPI); "" = the build's
  std::string viewer_dir;                // viewer.html + Cesium/; "" = the build's
  std::string token;                     // bearer token; "" = no authentication
  // Origins whose pages may call the API (CORS), e.g. "https://example.org"; "*" = any;
  // none = no cross-origin access. Preflights (OPTIONS) need no token.
  std::vector<std::string> cors_origins;
  size_t max_body_bytes = 1 << 20;       // request body limit, bytes, >= 1024
  int http_threads = 32;                 // concurrent HTTP connections served, [1, 1024]
  int max_stream_s = 3600;               // progress stream lifetime, s, >= 1
  double memory_budget_mb = 0;           // a worker's memory budget for jobs that set no
                                         // tiling.memory_budget_mb, MB, >= 0; 0: a quarter
                                         // of the machine's memory / scheduler.workers
  InputPolicy inputs;
  SchedulerOptions scheduler;            // the embedded queue (queue = "")
  // "" = the embedded queue (tiles run in this process); redis://HOST[:PORT][/DB] = an API
  // node of the Redis queue (redis_queue.h): tiles run on satmesh-worker processes.
  std::string queue;
  RedisQueueOptions redis;               // its settings (url taken from `queue`)
  std::string Check() const;
};

class ApiServer {
 public:
  // The executor must outlive the server.
  ApiServer(const ServerOptions& options, JobExecutor* executor);
  ~ApiServer();
  // Loads the job store, starts the workers and the HTTP listener; returns the bound port.
  // Throws Error{kIo} when the address cannot be bound.
  int Start();
  // Stops the listener, then the workers (running tiles return to the queue). Idempotent.
  void Stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace satmesh::server
