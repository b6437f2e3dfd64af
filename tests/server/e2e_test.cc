// End to end with the real engine: a tiny synthetic scene submitted over loopback, polled
// to success, the glb decoded and the metrics compared with an in-process run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/mesh/mesh_io.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/job.h"
#include "proto/job_spec_json.h"
#include "server/api_documents.h"
#include "server/real_executor.h"
#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

using nlohmann::json;

TEST(EndToEnd, SmallSyntheticSceneOverHttpMatchesInProcess) {
  const std::string dir = TempDir("e2e");
  const std::string scene = dir + "/scene";
  synth::SynthOptions synth_options = synth::SynthPreset("small", /*seed=*/1);
  synth_options.write_preview = false;
  const auto t0 = std::chrono::steady_clock::now();
  synth::GenerateScene(scene, synth_options);
  json job = ReadJsonFile(scene + "/job.json");
  job["options"]["levels"] = 1;
  job["options"]["iterations_per_level"] = 3;

  RealExecutor executor;
  ServerOptions options;
  options.port = 0;
  options.data_dir = dir + "/data";
  options.inputs.data_roots = {scene};
  options.scheduler.workers = 1;
  ApiServer server(options, &executor);
  const int port = server.Start();
  httplib::Client c("127.0.0.1", port);
  c.set_read_timeout(30, 0);
  const auto t1 = std::chrono::steady_clock::now();
  auto r = c.Post("/processes/refine-mesh/execution", job.dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string id = Json(r)["jobID"];
  json info;
  for (int i = 0; i < 3000; ++i) {  // <= 300 s
    info = Json(c.Get(("/jobs/" + id).c_str()));
    if (info["status"] != "accepted" && info["status"] != "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const auto t2 = std::chrono::steady_clock::now();
  ASSERT_EQ(info["status"], "successful") << info.dump();

  const json results = Json(c.Get(("/jobs/" + id + "/results").c_str()));
  ASSERT_FALSE(results["tiles"].empty());
  for (const auto& tile : results["tiles"]) {
    auto glb = c.Get(tile["href"].get<std::string>().c_str());
    ASSERT_EQ(glb->status, 200);
    std::ofstream(dir + "/tile.glb", std::ios::binary) << glb->body;
    EXPECT_GT(ReadMesh(dir + "/tile.glb").num_faces(), 100u);
  }
  EXPECT_EQ(c.Get(results["mesh"]["href"].get<std::string>().c_str())->status, 200);
  const json tileset = Json(c.Get(results["tileset"]["href"].get<std::string>().c_str()));
  EXPECT_EQ(tileset["asset"]["version"], "1.1");
  // The viewer's live tileset: every finished tile, as the assembled one.
  const json live = Json(c.Get(("/jobs/" + id + "/tileset.json").c_str()));
  EXPECT_EQ(live["extras"]["status"], "successful");
  EXPECT_EQ(live["root"]["children"].size(), tileset["root"]["children"].size());
  EXPECT_EQ(live["extras"]["tiles_done"], results["tiles"].size());
  for (size_t k = 0; k < 6; ++k)
    EXPECT_DOUBLE_EQ(live["root"]["boundingVolume"]["region"][k].get<double>(),
                     tileset["root"]["boundingVolume"]["region"][k].get<double>());
  // Every CRS is checked at submission, naming its field.
  for (const char* field : {"outputs", "aoi"}) {
    json bad = job;
    if (std::string(field) == "outputs") bad["outputs"]["crs"] = "EPSG:99999999";
    else bad["aoi"] = {{"bbox", {0, 0, 1, 1}}, {"crs", "EPSG:99999999"}};
    auto refused = c.Post("/processes/refine-mesh/execution", bad.dump(), "application/json");
    EXPECT_EQ(refused->status, 400) << refused->body;
    EXPECT_NE(Json(refused)["detail"].get<std::string>().find(std::string(field) + ".crs: 'EPSG:99999999'"),
              std::string::npos) << refused->body;
  }
  const json served = results["metrics"]["value"];

  // The same job in-process (the CLI's path).
  const JobSpec spec = proto::JobSpecFromJson(job, scene);
  const JobOutputs local = RunJob(spec, dir + "/local");
  const json expected = proto::JobMetricsToJson(local);
  const auto t3 = std::chrono::steady_clock::now();
  ASSERT_EQ(served["tiles"].size(), expected["tiles"].size());
  for (size_t t = 0; t < expected["tiles"].size(); ++t) {
    const json& a = served["tiles"][t];
    const json& b = expected["tiles"][t];
    EXPECT_EQ(a["name"], b["name"]);
    EXPECT_EQ(a["faces"], b["faces"]);
    EXPECT_EQ(a["vertices"], b["vertices"]);
    ASSERT_EQ(a["levels"].size(), b["levels"].size());
    for (size_t l = 0; l < b["levels"].size(); ++l) {
      EXPECT_NEAR(a["levels"][l]["mean_zncc_end"].get<double>(),
                  b["levels"][l]["mean_zncc_end"].get<double>(), 1e-4);
    }
  }
  EXPECT_EQ(served["totals"]["faces"], expected["totals"]["faces"]);
  const auto s = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
  std::printf("[ e2e ] synth %.1f s, submit->successful over HTTP %.1f s, in-process run %.1f s, "
              "%zu tile(s)\n", s(t0, t1), s(t1, t2), s(t2, t3), expected["tiles"].size());
  server.Stop();
}

}  // namespace
}  // namespace satmesh::server::testing
