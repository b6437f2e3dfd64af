// The stub server as a separate process: kill -9 mid-job, restart on the same data
// directory, the job completes with every tile finished exactly once.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "tests/server/process_util.h"
#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

TEST(Process, KillDashNineMidJobThenRestartCompletesEveryTileOnce) {
  const std::string dir = TempDir("kill9");
  const nlohmann::json job = MakeStubJob(dir + "/root");
  Child first = Spawn(dir);
  ASSERT_GT(first.port, 0);
  httplib::Client c("127.0.0.1", first.port);
  auto r = c.Post("/processes/refine-mesh/execution", job.dump(), "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 201);
  const std::string id = Json(r)["jobID"];
  int done_before = 0;
  std::set<std::string> acknowledged;  // tiles the first server reported done
  for (int i = 0; i < 1000 && done_before < 3; ++i) {
    const auto tiles = Json(c.Get(("/jobs/" + id + "/tiles").c_str()))["tiles"];
    acknowledged.clear();
    for (const auto& t : tiles)
      if (t["status"] == "done") acknowledged.insert(std::to_string(t["x"].get<int>()) + "_" + std::to_string(t["y"].get<int>()));
    done_before = int(acknowledged.size());
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(first.pid, SIGKILL);
  waitpid(first.pid, nullptr, 0);
  ASSERT_GE(done_before, 3);

  Child second = Spawn(dir);
  ASSERT_GT(second.port, 0);
  httplib::Client c2("127.0.0.1", second.port);
  nlohmann::json info;
  for (int i = 0; i < 1000; ++i) {
    info = Json(c2.Get(("/jobs/" + id).c_str()));
    if (info["status"] == "successful") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(info["status"], "successful") << info.dump();
  const nlohmann::json tiles = Json(c2.Get(("/jobs/" + id + "/tiles").c_str()))["tiles"];
  int rerun = 0;
  for (const auto& t : tiles) rerun += t["attempts"].get<int>() > 1;
  std::map<std::string, int> count;
  std::ifstream log(dir + "/data/jobs/" + id + "/completions.log");
  for (std::string line; std::getline(log, line);) ++count[line];
  EXPECT_EQ(count.size(), 8u);
  // A tile reported done is never run again. A tile killed mid-run re-runs; in the rare
  // case that it had just finished but was not yet recorded, its files are rewritten
  // identically (temporary name + rename), so its log may show it twice.
  int finished_twice = 0;
  for (const auto& [tile, n] : count) {
    if (acknowledged.count(tile)) EXPECT_EQ(n, 1) << "tile " << tile << " finished " << n << " times";
    else EXPECT_LE(n, 2) << tile;
    finished_twice += n > 1;
  }
  for (const auto& t : tiles) EXPECT_EQ(t["status"], "done");
  std::printf("[ kill -9 ] %d of 8 tiles done before the kill, %d interrupted tile(s) re-run, "
              "%zu tiles finished, %d finished twice\n", done_before, rerun, count.size(), finished_twice);
  kill(second.pid, SIGTERM);
  int status = 0;
  waitpid(second.pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

}  // namespace
}  // namespace satmesh::server::testing
