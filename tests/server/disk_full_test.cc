// The data directory's disk fills up mid-job (a real 4 MiB tmpfs, so needs root: skipped
// otherwise). The tile's write fails with "No space left on device"; the job stays running
// and readable (GET and state.json), no partial or temporary tile is left or served; when
// space comes back the tile is retried and the job finishes.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/synth/scene_writer.h"
#include "server/api_documents.h"
#include "server/real_executor.h"
#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct TmpfsMount {
  std::string dir;
  bool mounted = false;
  TmpfsMount(const std::string& path, const std::string& size) : dir(path) {
    fs::create_directories(dir);
    mounted = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
  }
  ~TmpfsMount() {
    if (mounted) ::umount2(dir.c_str(), MNT_DETACH);
  }
};

// Fills the file system of `path` until fewer than `leave_bytes` are free.
void FillDisk(const std::string& path, uintmax_t leave_bytes) {
  std::ofstream out(path, std::ios::binary);
  const std::string block(4096, 'x');
  while (fs::space(fs::path(path).parent_path()).available > leave_bytes && out.write(block.data(), block.size())) out.flush();
}

TEST(DiskFull, TileWaitsForSpaceNothingHalfWrittenIsServedAndTheJobResumes) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to mount a small tmpfs";
  const std::string dir = TempDir("disk_full");
  TmpfsMount data(dir + "/data", "4m");
  if (!data.mounted) GTEST_SKIP() << "cannot mount a tmpfs here (container without CAP_SYS_ADMIN?)";
  const std::string scene = dir + "/scene";
  synth::SynthOptions o = synth::SynthPreset("small", /*seed=*/1);
  o.city.aoi_size_m = 24;
  o.city.ground_margin_m = 20;
  o.city.building_margin_m = 4;
  o.render.supersample = 1;
  o.write_preview = false;
  synth::GenerateScene(scene, o);
  json job = ReadJsonFile(scene + "/job.json");
  job["options"]["levels"] = 1;
  job["options"]["iterations_per_level"] = 2;

  RealExecutor executor;
  ServerOptions options;
  options.port = 0;
  options.data_dir = data.dir;
  options.inputs.data_roots = {scene};
  options.scheduler.workers = 1;
  options.scheduler.no_space_retry_s = 0.3;
  ApiServer server(options, &executor);
  httplib::Client c("127.0.0.1", server.Start());
  c.set_read_timeout(30, 0);
  // Room for the job's request and state (a few KB), not for its tile (~100 KB of glb).
  FillDisk(data.dir + "/filler", 24 << 10);
  auto r = c.Post("/processes/refine-mesh/execution", job.dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string id = Json(r)["jobID"];
  json info = json::object();
  for (int i = 0; i < 600 && info.value("message", "").find("waiting for disk space") == std::string::npos; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    info = Json(c.Get(("/jobs/" + id).c_str()));
  }
  EXPECT_EQ(info["status"], "running") << info.dump();
  EXPECT_NE(info.value("message", "").find("No space left on device"), std::string::npos) << info.dump();
  const json tiles = Json(c.Get(("/jobs/" + id + "/tiles").c_str()));
  EXPECT_NE(tiles.dump().find("No space left on device"), std::string::npos) << tiles.dump();
  // Nothing half-written: no glb, no partial file; the tile is not served.
  const fs::path job_dir = fs::path(data.dir) / "jobs" / id;
  for (const auto& entry : fs::directory_iterator(job_dir / "tiles")) ADD_FAILURE() << "left behind: " << entry.path();
  EXPECT_EQ(c.Get(("/jobs/" + id + "/tiles/0_0.glb").c_str())->status, 404);
  // The state on disk stays whole JSON (written atomically; a failed save keeps the last).
  std::ifstream state(job_dir / "state.json");
  EXPECT_NO_THROW(json::parse(state));

  fs::remove(data.dir + "/filler");  // space is back
  for (int i = 0; i < 600 && info["status"] == "running"; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    info = Json(c.Get(("/jobs/" + id).c_str()));
  }
  EXPECT_EQ(info["status"], "successful") << info.dump();
  auto glb = c.Get(("/jobs/" + id + "/tiles/0_0.glb").c_str());
  EXPECT_EQ(glb->status, 200);
  EXPECT_GT(glb->body.size(), 10000u);
  const json tile = Json(c.Get(("/jobs/" + id + "/tiles").c_str()))["tiles"][0];
  EXPECT_GE(tile.value("attempts", 0), 2) << tile.dump();
  server.Stop();
}

}  // namespace
}  // namespace satmesh::server::testing
