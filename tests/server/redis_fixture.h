#pragma once
// The Redis queue's test fixture (issue 22): a real redis-server on loopback (random port,
// own folder, AOF on), real satmesh-server API nodes (--queue) and satmesh-worker
// processes, the small synthetic scene of the server's end-to-end tests cut into 2 x 2
// tiles. Tests on it skip when redis-server is not installed.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "core/mesh/mesh_io.h"
#include "core/synth/scene_writer.h"
#include "tests/tiny_scene.h"
#include "core/tiling/job.h"
#include "proto/job_spec_json.h"
#include "server/api_documents.h"
#include "server/redis_client.h"
#include "server/redis_queue.h"
#include "server/redis_worker.h"
#include "server/server_cli.h"
#include "tests/server/test_server.h"

namespace satmesh::server::testing {

using nlohmann::json;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

inline constexpr const char* kRedisServer = "/usr/bin/redis-server";

inline int FreePort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  socklen_t len = sizeof addr;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  ::close(fd);
  return ntohs(addr.sin_port);
}

// A child process; stdout and stderr to `log`. With `port_from_stdout`, reads "listening
// on port N" from its stdout first.
struct Process {
  pid_t pid = -1;
  int port = 0;
  static Process Start(const std::vector<std::string>& argv, const std::string& log, bool port_from_stdout = false) {
    int out[2];
    if (port_from_stdout && pipe(out) != 0) return {};
    const pid_t pid = fork();
    if (pid == 0) {
      FILE* f = std::fopen(log.c_str(), "a");
      if (f) dup2(fileno(f), STDERR_FILENO);
      if (port_from_stdout) {
        dup2(out[1], STDOUT_FILENO);
        close(out[0]);
      } else if (f) {
        dup2(fileno(f), STDOUT_FILENO);
      }
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    Process p;
    p.pid = pid;
    if (port_from_stdout) {
      close(out[1]);
      FILE* f = fdopen(out[0], "r");
      char line[256] = {0};
      while (fgets(line, sizeof line, f))
        if (std::sscanf(line, "listening on port %d", &p.port) == 1) break;
    }
    return p;
  }
  void Kill(int signal = SIGKILL) {
    if (pid <= 0) return;
    ::kill(pid, signal);
    int status = 0;
    waitpid(pid, &status, 0);
    pid = -1;
  }
};

class RedisQueue : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kRedisServer)) GTEST_SKIP() << "redis-server is not installed (Debian: apt-get install redis-server)";
    dir_ = TempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    apis_.reserve(8);  // StartApi/StartWorker hand out references into these: at most
    workers_.reserve(64);  // 8 API nodes and 64 workers per test
    data_ = dir_ + "/data";
    fs::create_directories(dir_ + "/redis");
    redis_port_ = FreePort();
    url_ = "redis://127.0.0.1:" + std::to_string(redis_port_);
    StartRedis();
  }
  // (Again after a stop: the same port and folder, the AOF read back.)
  void StartRedis() {
    redis_ = Process::Start({kRedisServer, "--port", std::to_string(redis_port_), "--bind", "127.0.0.1", "--dir",
                             dir_ + "/redis", "--save", "", "--appendonly", "yes", "--appendfsync", "always",
                             "--daemonize", "no"},
                            dir_ + "/redis.log");
    RedisConnection redis(ParseRedisUrl(url_));
    for (int i = 0; i < 100; ++i) {
      try {
        if (redis.Command({"PING"}).str == "PONG") return;
      } catch (const std::exception&) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    FAIL() << "redis-server did not answer on port " << redis_port_;
  }
  void TearDown() override {
    if (HasFailure())  // the processes' logs
      for (const auto& entry : fs::directory_iterator(dir_))
        if (entry.path().extension() == ".log") {
          std::ifstream in(entry.path());
          const std::string text(std::istreambuf_iterator<char>(in), {});
          std::printf("---- %s (last 3000 bytes)\n%s\n", entry.path().filename().c_str(),
                      text.substr(text.size() > 3000 ? text.size() - 3000 : 0).c_str());
        }
    for (auto& p : workers_) p.Kill(SIGTERM);
    for (auto& p : apis_) p.Kill(SIGTERM);
    redis_.Kill(SIGTERM);
  }

  // The scene: 36 m AOI, 2 x 2 tiles of 18 m, one coarse level (as tests/core/tiling).
  json MakeJob(int iterations, double aoi_size_m = 36, bool estimate_bias = false) {
    scene_ = dir_ + "/scene";
    const synth::SynthOptions o = satmesh::testing::TinySceneOptions(aoi_size_m);
    synth::GenerateScene(scene_, o);
    json job = ReadJsonFile(scene_ + "/job.json");
    job["options"]["levels"] = 1;
    job["options"]["iterations_per_level"] = iterations;
    job["options"]["estimate_bias"] = estimate_bias;
    job["tiling"] = {{"size_m", 18}, {"overlap_m", 3}};
    return job;
  }
  Process& StartApi() {
    apis_.push_back(Process::Start({SATMESH_SERVER, "--port", "0", "--data-dir", data_, "--data-root", scene_,
                                    "--queue", url_},
                                   dir_ + "/api" + std::to_string(apis_.size()) + ".log", /*port_from_stdout=*/true));
    EXPECT_GT(apis_.back().port, 0);
    return apis_.back();
  }
  // `extra`: more satmesh-worker arguments (e.g. --memory-budget MB).
  Process& StartWorker(double idle_timeout_s = 30, int max_deliveries = 3,
                       const std::vector<std::string>& extra = {}) {
    const std::string name = "w" + std::to_string(workers_.size());
    std::vector<std::string> argv = {SATMESH_WORKER, "--queue", url_, "--data-dir", data_, "--threads", "1",
                                     "--idle-timeout-s", std::to_string(idle_timeout_s), "--max-deliveries",
                                     std::to_string(max_deliveries), "--name", name};
    argv.insert(argv.end(), extra.begin(), extra.end());
    workers_.push_back(Process::Start(argv, dir_ + "/" + name + ".log"));
    return workers_.back();
  }
  static httplib::Client Client(const Process& api) {
    httplib::Client c("127.0.0.1", api.port);
    c.set_read_timeout(30, 0);
    return c;
  }
  static std::string Submit(const Process& api, const json& job) {
    auto r = Client(api).Post("/processes/refine-mesh/execution", json{{"inputs", {{"job", job}}}}.dump(),
                              "application/json");
    EXPECT_TRUE(r && r->status == 201) << (r ? r->body : "no answer");
    return r && r->status == 201 ? Json(r)["jobID"].get<std::string>() : "";
  }
  static json WaitEnd(const Process& api, const std::string& id, double timeout_s = 300) {
    json info;
    const auto until = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (Clock::now() < until) {
      const auto r = Client(api).Get(("/jobs/" + id).c_str());
      if (r && r->status == 200) {  // (not while Redis restarts: 500)
        info = Json(r);
        if (info["status"] != "accepted" && info["status"] != "running") break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return info;
  }

  std::string dir_, data_, scene_, url_;
  int redis_port_ = 0;
  Process redis_;
  std::vector<Process> apis_, workers_;
};

// Every tile's result once, done; the metrics' tiles named once each.
inline void ExpectEveryTileOnce(const json& tiles, const json& metrics, size_t n) {
  ASSERT_EQ(tiles.size(), n);
  for (const auto& t : tiles) EXPECT_EQ(t["status"], "done") << t.dump();
  std::set<std::string> names;
  for (const auto& t : metrics["tiles"]) names.insert(t["name"].get<std::string>());
  EXPECT_EQ(names.size(), n);
  EXPECT_EQ(metrics["tiles"].size(), n);
}

}  // namespace satmesh::server::testing
