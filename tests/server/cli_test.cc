// The real `satmesh` client against the stub server process: submit --wait, status,
// jobs, results --out, cancel, and the exit codes scripts rely on.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/mesh/mesh_io.h"
#include "tests/server/process_util.h"
#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

struct CliRun {
  int code = -1;
  std::string out;
};

CliRun Cli(const std::string& args) {
  const std::string command = std::string(SATMESH_CLI) + " " + args + " 2>/dev/null";
  FILE* p = popen(command.c_str(), "r");
  CliRun run;
  std::array<char, 4096> buf{};
  while (p && fgets(buf.data(), int(buf.size()), p)) run.out += buf.data();
  const int status = p ? pclose(p) : -1;
  run.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

TEST(Cli, SubmitWaitStatusJobsResultsCancel) {
  const std::string dir = TempDir("cli");
  const nlohmann::json job = MakeStubJob(dir + "/root");
  std::ofstream(dir + "/root/job.json") << job.dump();
  Child server = Spawn(dir, 2, 1, 100);
  ASSERT_GT(server.port, 0);
  const std::string url = " --server http://127.0.0.1:" + std::to_string(server.port);

  const CliRun submit = Cli("submit " + dir + "/root/job.json --wait --quiet --poll 0.05" + url);
  ASSERT_EQ(submit.code, 0) << submit.out;
  const std::string id = submit.out.substr(0, submit.out.find('\n'));
  ASSERT_EQ(id.size(), 16u) << submit.out;

  const CliRun status = Cli("status " + id + url);
  EXPECT_EQ(status.code, 0);
  EXPECT_NE(status.out.find("successful"), std::string::npos) << status.out;
  EXPECT_NE(Cli("jobs --status successful" + url).out.find(id), std::string::npos);

  const CliRun results = Cli("results " + id + " --out " + dir + "/out" + url);
  ASSERT_EQ(results.code, 0) << results.out;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/tileset.json"));
  EXPECT_TRUE(std::filesystem::exists(dir + "/out/metrics.json"));
  for (const char* tile : {"0_0", "1_0"})
    EXPECT_EQ(ReadMesh(dir + "/out/tiles/" + tile + ".glb").num_faces(), 1u) << tile;

  EXPECT_EQ(Cli("status 0123456789abcdef" + url).code, 4);       // not found
  EXPECT_EQ(Cli("status").code, 2);                               // usage
  EXPECT_EQ(Cli("jobs --server http://127.0.0.1:1").code, 5);     // unreachable
  EXPECT_EQ(Cli("submit " + dir + "/root/missing.json" + url).code, 2);

  // A slow job: cancel it mid-run; wait then reports it dismissed (exit 3).
  std::ofstream(dir + "/root/slow.json") << job.dump();
  const CliRun second = Cli("submit " + dir + "/root/slow.json" + url);
  ASSERT_EQ(second.code, 0);
  const std::string slow = second.out.substr(0, second.out.find('\n'));
  const CliRun cancel = Cli("cancel " + slow + url);
  EXPECT_EQ(cancel.code, 0);
  EXPECT_NE(cancel.out.find("dismissed"), std::string::npos) << cancel.out;
  EXPECT_EQ(Cli("wait " + slow + " --quiet" + url).code, 3);
  EXPECT_EQ(Cli("results " + slow + " --out " + dir + "/out2" + url).code, 4);
  EXPECT_EQ(Stop(server), 0);
}

TEST(Cli, SubmitResolvesRelativeHrefsAgainstTheJobFileOrSaysWhatToDo) {
  const std::string dir = TempDir("cli_hrefs");
  const nlohmann::json job = MakeStubJob(dir + "/root");  // relative hrefs: a.tif, b.tif, dsm.tif
  // A scene one folder below the data root, with files only there.
  std::filesystem::create_directories(dir + "/root/scene");
  for (const char* name : {"c.tif", "d.tif", "scene_dsm.tif"}) std::ofstream(dir + "/root/scene/" + name) << "stub";
  nlohmann::json scene_job = job;
  scene_job["images"] = {{{"href", "c.tif"}}, {{"href", "d.tif"}}};
  scene_job["initial"]["dsm"] = "scene_dsm.tif";
  std::ofstream(dir + "/root/scene/job.json") << scene_job.dump();
  Child server = Spawn(dir, 2, 1, 10);
  ASSERT_GT(server.port, 0);
  const std::string url = " --server http://127.0.0.1:" + std::to_string(server.port);
  // Its hrefs resolve against the job file's folder (not the server's root, where
  // c.tif is not).
  const CliRun ok = Cli("submit " + dir + "/root/scene/job.json --wait --quiet --poll 0.05" + url);
  EXPECT_EQ(ok.code, 0) << ok.out;
  // Outside every data root: refused, and the message says what to do.
  std::filesystem::create_directories(dir + "/elsewhere");
  for (const char* name : {"a.tif", "b.tif", "dsm.tif"})
    std::filesystem::copy_file(dir + "/root/" + name, dir + "/elsewhere/" + name);
  std::ofstream(dir + "/elsewhere/job.json") << job.dump();
  const CliRun refused = Cli("submit " + dir + "/elsewhere/job.json" + url + " 2>&1");
  EXPECT_NE(refused.code, 0);
  EXPECT_NE(refused.out.find("images[0].href"), std::string::npos) << refused.out;
  EXPECT_NE(refused.out.find("--data-root " + dir + "/elsewhere"), std::string::npos) << refused.out;
  EXPECT_NE(refused.out.find("--as-written"), std::string::npos) << refused.out;
  // --as-written: the server resolves them against its root (where a.tif etc. are).
  const CliRun as_written = Cli("submit " + dir + "/elsewhere/job.json --as-written --wait --quiet --poll 0.05" + url);
  EXPECT_EQ(as_written.code, 0) << as_written.out;
  EXPECT_EQ(Stop(server), 0);
}

}  // namespace
}  // namespace satmesh::server::testing
