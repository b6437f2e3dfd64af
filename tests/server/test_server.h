#pragma once
// An in-process satmesh-server on 127.0.0.1 (ephemeral port) with the stub engine, in a
// fresh temporary data directory, and helpers to talk to it.
// Eigen (through server/api.h) before httplib.h: glibc's <resolv.h> defines _res.
#include "server/api.h"
#include "tests/server/stub_executor.h"

#include <httplib.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include "tests/scratch_dir.h"

namespace satmesh::server::testing {

inline std::string TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("satmesh_server_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  satmesh::testing::RemoveAtExit(dir);
  return dir.string();
}

struct TestServer {
  std::string dir, root;
  ServerOptions options;
  std::unique_ptr<StubExecutor> executor;
  std::unique_ptr<ApiServer> server;
  int port = 0;

  // `configure` may change options before the start.
  explicit TestServer(const std::string& name, StubOptions stub = {}, int workers = 2,
                      const std::string& token = "", bool fresh = true) {
    dir = fresh ? TempDir(name) : (std::filesystem::temp_directory_path() /
                                   ("satmesh_server_test_" + name + "_" + std::to_string(::getpid()))).string();
    root = dir + "/root";
    std::filesystem::create_directories(root);
    options.port = 0;
    options.data_dir = dir + "/data";
    options.inputs.data_roots = {root};
    options.inputs.max_images = 8;
    options.scheduler.workers = workers;
    options.token = token;
    executor = std::make_unique<StubExecutor>(stub);
  }
  void Start() {
    server = std::make_unique<ApiServer>(options, executor.get());
    port = server->Start();
  }
  void Stop() { if (server) server->Stop(); }
  ~TestServer() { Stop(); }
  httplib::Client Client() const {
    httplib::Client c("127.0.0.1", port);
    c.set_read_timeout(10, 0);
    return c;
  }
};

inline nlohmann::json Json(const httplib::Result& r) {
  return r && !r->body.empty() ? nlohmann::json::parse(r->body) : nlohmann::json();
}

// Polls GET /jobs/{id} until the status is `status` (at most ~timeout_ms); returns the last statusInfo.
inline nlohmann::json WaitFor(const TestServer& s, const std::string& id, const std::string& status,
                              int timeout_ms = 10000) {
  auto client = s.Client();
  nlohmann::json info;
  for (int waited = 0; waited < timeout_ms; waited += 10) {
    info = Json(client.Get(("/jobs/" + id).c_str()));
    if (info.value("status", "") == status) return info;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return info;
}

inline std::string Submit(const TestServer& s, const nlohmann::json& job) {
  auto r = s.Client().Post("/processes/refine-mesh/execution", job.dump(), "application/json");
  if (!r || r->status != 201) return "";
  return Json(r)["jobID"];
}

}  // namespace satmesh::server::testing
