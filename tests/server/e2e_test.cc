// End to end with the real engine: a tiny synthetic scene submitted over loopback, polled
// to success, the glb decoded and the metrics compared with an in-process run.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <fstream>

#include "core/dsm/dsm.h"
#include "core/mesh/mesh_io.h"
#include "core/synth/scene_writer.h"
#include "tests/tiny_scene.h"
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
  // The pictures: a hillshade preview and the convergence plot, as PNG.
  for (const char* picture : {"preview", "convergence"}) {
    ASSERT_TRUE(results.contains(picture)) << results.dump();
    auto png = c.Get(results[picture]["href"].get<std::string>().c_str());
    ASSERT_EQ(png->status, 200) << picture;
    EXPECT_EQ(png->get_header_value("Content-Type"), "image/png");
    EXPECT_EQ(png->body.substr(1, 3), "PNG");
  }
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

TEST(EndToEnd, MultiTileMetricsAreFilledAsInProcess) {
  const std::string dir = TempDir("e2e_tiles");
  const std::string scene = dir + "/scene";
  synth::SynthOptions synth_options = synth::SynthPreset("small", /*seed=*/2);
  synth_options.write_preview = false;
  synth::GenerateScene(scene, synth_options);
  json job = ReadJsonFile(scene + "/job.json");
  job["options"]["iterations_per_level"] = 3;
  job["tiling"] = {{"size_m", 40}, {"overlap_m", 8}};  // 72 m scene: 2 x 2 tiles

  RealExecutor executor;
  ServerOptions options;
  options.port = 0;
  options.data_dir = dir + "/data";
  options.inputs.data_roots = {scene};
  options.scheduler.workers = 2;
  ApiServer server(options, &executor);
  httplib::Client c("127.0.0.1", server.Start());
  c.set_read_timeout(30, 0);
  auto r = c.Post("/processes/refine-mesh/execution", json{{"inputs", {{"job", job}}}}.dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string id = Json(r)["jobID"];
  json info;
  for (int i = 0; i < 3000; ++i) {
    info = Json(c.Get(("/jobs/" + id).c_str()));
    if (info["status"] != "accepted" && info["status"] != "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(info["status"], "successful") << info.dump();
  const json served = Json(c.Get(("/jobs/" + id + "/results").c_str()))["metrics"]["value"];
  ASSERT_EQ(served["tiles"].size(), 4u);

  // The job-level summary over the tiles: filled, and consistent with the tiles.
  EXPECT_NEAR(served["gsd_m"].get<double>(), 0.30, 0.01);
  EXPECT_EQ(served["views"].size(), 3u);
  ASSERT_FALSE(served["pairs"].empty());
  for (const auto& p : served["pairs"]) EXPECT_GE(p["tiles"].get<int>(), 1);
  ASSERT_FALSE(served["levels"].empty());
  const json& finest = served["levels"].back();
  EXPECT_EQ(finest["level"], 0);
  int faces = 0;
  double zncc_min = 1, zncc_max = -1;
  for (const auto& t : served["tiles"]) {
    faces += t["levels"].back()["faces"].get<int>();
    zncc_min = std::min(zncc_min, t["levels"].back()["mean_zncc_end"].get<double>());
    zncc_max = std::max(zncc_max, t["levels"].back()["mean_zncc_end"].get<double>());
  }
  EXPECT_EQ(finest["faces"], faces);
  EXPECT_GE(finest["mean_zncc_end"].get<double>(), zncc_min - 1e-9);  // a weighted mean of the tiles'
  EXPECT_LE(finest["mean_zncc_end"].get<double>(), zncc_max + 1e-9);
  EXPECT_GT(served["time_s"]["total"].get<double>(), 0.1);
  EXPECT_GT(served["totals"]["peak_rss_mb"].get<double>(), 10.0);

  // In-process (the CLI's path): the same summary.
  const JobOutputs local = RunJob(proto::JobSpecFromJson(job, scene), dir + "/local");
  const json expected = proto::JobMetricsToJson(local);
  EXPECT_EQ(served["views"], expected["views"]);
  EXPECT_NEAR(served["gsd_m"].get<double>(), expected["gsd_m"].get<double>(), 1e-9);
  EXPECT_EQ(served["pairs"].size(), expected["pairs"].size());
  ASSERT_EQ(served["levels"].size(), expected["levels"].size());
  EXPECT_EQ(served["levels"].back()["faces"], expected["levels"].back()["faces"]);
  EXPECT_NEAR(served["levels"].back()["mean_zncc_end"].get<double>(),
              expected["levels"].back()["mean_zncc_end"].get<double>(), 1e-4);
  EXPECT_GT(expected["totals"]["peak_rss_mb"].get<double>(), 10.0);
  server.Stop();
}

// The failure policy of core/tiling/job.h through the server, as in-process: a tile with
// no surface (the east half of the initial DSM is nodata) fails that tile only; the job is
// assembled from the others, equal to RunJob's.
TEST(EndToEnd, AFailingTileFailsThatTileOnlyAsInProcess) {
  const std::string dir = TempDir("e2e_failing_tile");
  const std::string scene = dir + "/scene";
  const synth::SynthOptions o = satmesh::testing::TinySceneOptions();
  synth::GenerateScene(scene, o);
  Dsm initial = ReadDsm(scene + "/initial/dsm.tif");
  for (int j = 0; j < initial.height; ++j)
    for (int i = initial.width / 2 - 10; i < initial.width; ++i) initial.at(i, j) = NAN;
  WriteDsm(scene + "/half.tif", initial);
  json job = ReadJsonFile(scene + "/job.json");
  job["initial"]["dsm"] = "half.tif";
  job["options"]["levels"] = 1;
  job["options"]["iterations_per_level"] = 1;
  job["options"]["estimate_bias"] = false;
  job["tiling"] = {{"size_m", 18}, {"overlap_m", 3}};  // 2 x 2 tiles

  RealExecutor executor;
  ServerOptions options;
  options.port = 0;
  options.data_dir = dir + "/data";
  options.inputs.data_roots = {scene};
  options.scheduler.workers = 2;
  ApiServer server(options, &executor);
  httplib::Client c("127.0.0.1", server.Start());
  c.set_read_timeout(30, 0);
  auto r = c.Post("/processes/refine-mesh/execution", json{{"inputs", {{"job", job}}}}.dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string id = Json(r)["jobID"];
  json info;
  for (int i = 0; i < 3000; ++i) {
    info = Json(c.Get(("/jobs/" + id).c_str()));
    if (info["status"] != "accepted" && info["status"] != "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(info["status"], "successful") << info.dump();
  EXPECT_NE(info["message"].get<std::string>().find("2 of 4 tiles failed"), std::string::npos) << info.dump();
  const json tiles = Json(c.Get(("/jobs/" + id + "/tiles").c_str()))["tiles"];
  ASSERT_EQ(tiles.size(), 4u);
  for (const auto& t : tiles) {
    EXPECT_EQ(t["status"], t["x"] == 1 ? "failed" : "done") << t.dump();
    if (t["x"] == 1) {
      EXPECT_NE(t["message"].get<std::string>().find("no valid cell"), std::string::npos) << t.dump();
    }
  }
  const json served = Json(c.Get(("/jobs/" + id + "/results").c_str()))["metrics"]["value"];
  server.Stop();

  const JobOutputs local = RunJob(proto::JobSpecFromJson(job, scene), dir + "/local");
  const json expected = proto::JobMetricsToJson(local);
  EXPECT_EQ(local.assembly.tiles_failed, 2);
  EXPECT_EQ(served["totals"]["successful"], expected["totals"]["successful"]);
  EXPECT_EQ(served["totals"]["failed"], expected["totals"]["failed"]);
  EXPECT_EQ(served["totals"]["faces"], expected["totals"]["faces"]);
  ASSERT_EQ(served["tiles"].size(), expected["tiles"].size());
  for (size_t t = 0; t < expected["tiles"].size(); ++t) {
    EXPECT_EQ(served["tiles"][t]["status"], expected["tiles"][t]["status"]);
    EXPECT_EQ(served["tiles"][t].value("error", json()), expected["tiles"][t].value("error", json()));
  }
}

// Bad data is refused at submission with 422 and the checker's message (core/tiling/
// input_check.h, tested case by case in tests/core/tiling/input_check_test.cc); no job is made.
TEST(EndToEnd, BadDataIsRefusedAtSubmissionNamingFieldAndFile) {
  const std::string dir = TempDir("e2e_bad");
  const std::string scene = dir + "/scene";
  synth::SynthOptions o = synth::SynthPreset("small", /*seed=*/1);
  o.city.aoi_size_m = 24;
  o.city.ground_margin_m = 20;
  o.city.building_margin_m = 4;
  o.render.supersample = 1;
  o.write_preview = false;
  synth::GenerateScene(scene, o);
  const json job = ReadJsonFile(scene + "/job.json");
  const std::string first = job["images"][0]["href"];
  std::filesystem::copy_file(scene + "/" + first, scene + "/truncated.tif");
  std::filesystem::resize_file(scene + "/truncated.tif", std::filesystem::file_size(scene + "/truncated.tif") / 3);

  RealExecutor executor;
  ServerOptions options;
  options.port = 0;
  options.data_dir = dir + "/data";
  options.inputs.data_roots = {scene};
  options.scheduler.workers = 1;
  ApiServer server(options, &executor);
  httplib::Client c("127.0.0.1", server.Start());
  c.set_read_timeout(30, 0);
  const std::vector<std::pair<std::function<void(json&)>, std::string>> cases = {
      {[&](json& j) { j["images"].push_back(j["images"][0]); }, "images[3].href: '"},
      {[&](json& j) { j["images"][1]["href"] = "truncated.tif"; }, "images[1].href: '"}};
  const std::vector<std::string> why = {"is the same file as images[0].href", "(truncated or corrupt file?)"};
  for (size_t k = 0; k < cases.size(); ++k) {
    json bad = job;
    cases[k].first(bad);
    auto r = c.Post("/processes/refine-mesh/execution", bad.dump(), "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 422) << r->body;
    const std::string detail = Json(r).value("detail", "");
    EXPECT_NE(detail.find(cases[k].second), std::string::npos) << detail;
    EXPECT_NE(detail.find(why[k]), std::string::npos) << detail;
  }
  EXPECT_TRUE(Json(c.Get("/jobs"))["jobs"].empty());
  server.Stop();
}

}  // namespace
}  // namespace satmesh::server::testing
