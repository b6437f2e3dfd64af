#include "server/server_cli.h"

#include <spdlog/spdlog.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <pthread.h>

#include "core/common/error.h"

namespace satmesh::server {
namespace {

long long ToInteger(const std::string& key, const std::string& value) {
  try {
    size_t used = 0;
    const long long v = std::stoll(value, &used);
    if (used == value.size()) return v;
  } catch (const std::exception&) {
  }
  ThrowError(ErrorCode::kInvalidArgument, "--" + key + ": expected an integer, got '" + value + "'");
}

}  // namespace

std::string ServerUsage() {
  return "usage: satmesh-server [--host 127.0.0.1] [--port 8080] [--data-dir DIR]\n"
         "         [--data-root DIR ...] [--allow-vsi /vsicurl/ ...] [--workers 2]\n"
         "         [--token T | env SATMESH_TOKEN] [--max-body-bytes 1048576]\n"
         "         [--max-images 64] [--max-tiles 1024] [--max-pixels 4000000000]\n"
         "         [--max-mesh-faces 20000000]\n"
         "         [--http-threads 32] [--proto-dir DIR] [--viewer-dir DIR | env SATMESH_VIEWER_DIR]\n"
         "         [--cors-origin https://example.org ... | --cors-origin '*'] [--memory-budget MB]\n"
         "         [--queue redis://HOST:PORT[/DB] [--queue-prefix satmesh]]  (an API node: tiles run\n"
         "          on satmesh-worker processes with the same queue and prefix)\n";
}

ServerOptions ParseServerArgs(const std::vector<std::string>& args,
                              const std::vector<std::string>& extra_keys,
                              std::map<std::string, std::string>* extra) {
  ServerOptions o;
  if (const char* token = std::getenv("SATMESH_TOKEN")) o.token = token;
  if (const char* viewer = std::getenv("SATMESH_VIEWER_DIR")) o.viewer_dir = viewer;  // the image sets it
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    SATMESH_CHECK(arg.rfind("--", 0) == 0 && arg.size() > 2, ErrorCode::kInvalidArgument,
                  "unexpected argument '" + arg + "'\n" + ServerUsage());
    const std::string key = arg.substr(2);
    SATMESH_CHECK(i + 1 < args.size(), ErrorCode::kInvalidArgument, "--" + key + " needs a value");
    const std::string value = args[++i];
    if (key == "host") o.host = value;
    else if (key == "port") o.port = int(ToInteger(key, value));
    else if (key == "data-dir") o.data_dir = value;
    else if (key == "data-root") o.inputs.data_roots.push_back(value);
    else if (key == "allow-vsi") o.inputs.allowed_vsi.push_back(value);
    else if (key == "workers") o.scheduler.workers = int(ToInteger(key, value));
    else if (key == "token") o.token = value;
    else if (key == "max-body-bytes") o.max_body_bytes = size_t(ToInteger(key, value));
    else if (key == "max-images") o.inputs.max_images = int(ToInteger(key, value));
    else if (key == "max-tiles") o.inputs.max_tiles = int(ToInteger(key, value));
    else if (key == "max-pixels") o.inputs.max_pixels = ToInteger(key, value);
    else if (key == "max-mesh-faces") o.inputs.max_mesh_faces = size_t(ToInteger(key, value));
    else if (key == "http-threads") o.http_threads = int(ToInteger(key, value));
    else if (key == "proto-dir") o.proto_dir = value;
    else if (key == "viewer-dir") o.viewer_dir = value;
    else if (key == "cors-origin") o.cors_origins.push_back(value);
    else if (key == "memory-budget") o.memory_budget_mb = double(ToInteger(key, value));
    else if (key == "queue") o.queue = value;
    else if (key == "queue-prefix") o.redis.prefix = value;
    else {
      bool known = false;
      for (const auto& k : extra_keys) known = known || k == key;
      SATMESH_CHECK(known && extra, ErrorCode::kInvalidArgument, "unknown option --" + key + "\n" + ServerUsage());
      (*extra)[key] = value;
    }
  }
  const std::string problem = o.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, problem);
  return o;
}

int ServeUntilSignal(const ServerOptions& options, JobExecutor* executor) {
  // Block the signals in every thread; this one waits for them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  ApiServer server(options, executor);
  const int port = server.Start();
  std::printf("listening on port %d\n", port);
  std::fflush(stdout);
  int received = 0;
  sigwait(&signals, &received);
  spdlog::info("signal {}: stopping (running tiles stay queued)", received);
  server.Stop();
  return 0;
}

}  // namespace satmesh::server
