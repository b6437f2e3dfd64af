// The HTTP API over loopback with the stub engine (no refinement).
#include <gtest/gtest.h>

#include <fstream>

#include "core/mesh/mesh_io.h"
#include "core/tiling/memory_budget.h"
#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

using nlohmann::json;

TEST(Api, LandingConformanceAndProcessDescription) {
  TestServer s("landing");
  s.Start();
  auto c = s.Client();
  EXPECT_EQ(c.Get("/")->status, 200);
  EXPECT_FALSE(Json(c.Get("/conformance"))["conformsTo"].empty());
  EXPECT_EQ(Json(c.Get("/processes"))["processes"][0]["id"], "refine-mesh");
  const json d = Json(c.Get("/processes/refine-mesh"));
  EXPECT_TRUE(d["inputs"]["job"]["schema"]["properties"].contains("images"));
  EXPECT_EQ(Json(c.Get("/api"))["openapi"], "3.0.3");
  EXPECT_EQ(Json(c.Get("/health"))["status"], "ok");
}

TEST(Api, SubmitPollDownloadTilesAndResults) {
  TestServer s("submit");
  s.Start();
  auto c = s.Client();
  auto r = c.Post("/processes/refine-mesh/execution", MakeStubJob(s.root).dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const json info = Json(r);
  const std::string id = info["jobID"];
  EXPECT_EQ(r->get_header_value("Location"), "/jobs/" + id);
  EXPECT_EQ(info["tiles"]["total"], 4);
  const json done = WaitFor(s, id, "successful");
  ASSERT_EQ(done["status"], "successful") << done.dump();
  EXPECT_EQ(done["progress"], 100);
  EXPECT_EQ(done["tiles"]["done"], 4);
  const json tiles = Json(c.Get(("/jobs/" + id + "/tiles").c_str()));
  ASSERT_EQ(tiles["tiles"].size(), 4u);
  for (const auto& t : tiles["tiles"]) {
    auto glb = c.Get(t["href"].get<std::string>().c_str());
    ASSERT_EQ(glb->status, 200);
    EXPECT_EQ(glb->get_header_value("Content-Type"), "model/gltf-binary");
    const std::string path = s.dir + "/download.glb";
    std::ofstream(path, std::ios::binary) << glb->body;
    EXPECT_EQ(ReadMesh(path).num_faces(), 1u);
  }
  const json results = Json(c.Get(("/jobs/" + id + "/results").c_str()));
  EXPECT_EQ(results["metrics"]["value"]["tiles"], 4);
  const json tileset = Json(c.Get(results["tileset"]["href"].get<std::string>().c_str()));
  EXPECT_EQ(tileset["asset"]["version"], "1.1");
  EXPECT_EQ(tileset["root"]["children"].size(), 4u);
  const std::string uri = tileset["root"]["children"][0]["content"]["uri"];
  EXPECT_EQ(c.Get(("/jobs/" + id + "/results/" + uri).c_str())->status, 200);
}

TEST(Api, JobsGetTheServersMemoryBudgetUnlessTheyNameOne) {
  TestServer s("budget");
  s.options.memory_budget_mb = 3000;
  s.Start();
  auto c = s.Client();
  json job = MakeStubJob(s.root);
  ASSERT_EQ(c.Post("/processes/refine-mesh/execution", job.dump(), "application/json")->status, 201);
  EXPECT_EQ(s.executor->last_memory_budget_mb(), 3000);
  job["tiling"]["memory_budget_mb"] = 1500;
  ASSERT_EQ(c.Post("/processes/refine-mesh/execution", job.dump(), "application/json")->status, 201);
  EXPECT_EQ(s.executor->last_memory_budget_mb(), 1500);
  TestServer d("budget_default", {}, /*workers=*/4);
  d.Start();
  auto cd = d.Client();
  ASSERT_EQ(cd.Post("/processes/refine-mesh/execution", MakeStubJob(d.root).dump(), "application/json")->status, 201);
  EXPECT_DOUBLE_EQ(d.executor->last_memory_budget_mb(), DefaultMemoryBudgetMb(4));
}

TEST(Api, ResultNotReadyWhileRunning) {
  TestServer s("notready", Stub(1, 2, 400));
  s.Start();
  auto c = s.Client();
  const std::string id = Submit(s, MakeStubJob(s.root));
  ASSERT_FALSE(id.empty());
  auto r = c.Get(("/jobs/" + id + "/results").c_str());
  EXPECT_EQ(r->status, 404);
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/problem+json");
  EXPECT_NE(Json(r)["type"].get<std::string>().find("result-not-ready"), std::string::npos);
  EXPECT_EQ(c.Get(("/jobs/" + id + "/tiles/0_1.glb").c_str())->status, 404);
  EXPECT_EQ(WaitFor(s, id, "successful")["status"], "successful");
}

TEST(Api, DismissCancelsRunningTile) {
  TestServer s("dismiss", Stub(1, 1, 20000));
  s.Start();
  auto c = s.Client();
  const std::string id = Submit(s, MakeStubJob(s.root));
  ASSERT_EQ(WaitFor(s, id, "running")["status"], "running");
  auto r = c.Delete(("/jobs/" + id).c_str());
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(Json(r)["status"], "dismissed");
  json tiles;
  for (int i = 0; i < 500; ++i) {  // the stub checks every 10 ms
    tiles = Json(c.Get(("/jobs/" + id + "/tiles").c_str()));
    if (tiles["tiles"][0]["status"] == "cancelled") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(tiles["tiles"][0]["status"], "cancelled");
  EXPECT_EQ(c.Get(("/jobs/" + id + "/results").c_str())->status, 410);
  EXPECT_EQ(c.Delete("/jobs/nope")->status, 404);
}

TEST(Api, IdempotencyKeyReturnsTheFirstJob) {
  TestServer s("idem", Stub(1, 1, 10));
  s.Start();
  auto c = s.Client();
  const json job = MakeStubJob(s.root);
  const httplib::Headers key = {{"Idempotency-Key", "abc-1"}};
  auto first = c.Post("/processes/refine-mesh/execution", key, job.dump(), "application/json");
  auto second = c.Post("/processes/refine-mesh/execution", key, job.dump(), "application/json");
  ASSERT_EQ(first->status, 201);
  ASSERT_EQ(second->status, 200);
  EXPECT_EQ(Json(first)["jobID"], Json(second)["jobID"]);
  json other = job;
  other["options"]["levels"] = 2;
  EXPECT_EQ(c.Post("/processes/refine-mesh/execution", key, other.dump(), "application/json")->status, 422);
  EXPECT_EQ(Json(c.Get("/jobs"))["jobs"].size(), 1u);
}

TEST(Api, BearerTokenRequiredExceptHealth) {
  TestServer s("token", Stub(1, 1, 10), 1, "s3cret");
  s.Start();
  auto c = s.Client();
  EXPECT_EQ(c.Get("/health")->status, 200);
  auto r = c.Get("/jobs");
  EXPECT_EQ(r->status, 401);
  EXPECT_EQ(r->get_header_value("WWW-Authenticate"), "Bearer");
  c.set_bearer_token_auth("wrong");
  EXPECT_EQ(c.Get("/jobs")->status, 401);
  c.set_bearer_token_auth("s3cret");
  EXPECT_EQ(c.Get("/jobs")->status, 200);
}

TEST(Api, FailingTileFailsTheJob) {
  TestServer s("fail", Stub(2, 1, 10, "1_0"));
  s.Start();
  const std::string id = Submit(s, MakeStubJob(s.root));
  const json info = WaitFor(s, id, "failed");
  ASSERT_EQ(info["status"], "failed");
  EXPECT_NE(info["message"].get<std::string>().find("tile 1_0"), std::string::npos);
  EXPECT_EQ(s.Client().Get(("/jobs/" + id + "/results").c_str())->status, 422);
}

TEST(Api, JobListFiltersAndLimit) {
  TestServer s("list", Stub(1, 1, 10));
  s.Start();
  auto c = s.Client();
  std::vector<std::string> ids;
  for (int i = 0; i < 3; ++i) ids.push_back(Submit(s, MakeStubJob(s.root)));
  for (const auto& id : ids) WaitFor(s, id, "successful");
  EXPECT_EQ(Json(c.Get("/jobs?status=successful"))["jobs"].size(), 3u);
  EXPECT_EQ(Json(c.Get("/jobs?status=running"))["jobs"].size(), 0u);
  EXPECT_EQ(Json(c.Get("/jobs?limit=2"))["jobs"].size(), 2u);
  EXPECT_EQ(c.Get("/jobs?status=bogus")->status, 400);
}

TEST(Api, EventStreamEndsWithTheFinalStatus) {
  TestServer s("events", Stub(2, 1, 100));
  s.Start();
  const std::string id = Submit(s, MakeStubJob(s.root));
  std::string stream;
  auto r = s.Client().Get(("/jobs/" + id + "/events").c_str(), [&](const char* data, size_t n) {
    stream.append(data, n);
    return stream.size() < (1 << 20);
  });
  ASSERT_TRUE(r);
  EXPECT_EQ(r->get_header_value("Content-Type"), "text/event-stream");
  const auto last = stream.rfind("data: ");
  ASSERT_NE(last, std::string::npos);
  const json info = json::parse(stream.substr(last + 6, stream.find('\n', last) - last - 6));
  EXPECT_EQ(info["status"], "successful");
  EXPECT_GE(std::count(stream.begin(), stream.end(), '\n'), 6);  // several events
}

TEST(Api, MetricsCountTiles) {
  TestServer s("metrics", Stub(2, 2, 10));
  s.Start();
  WaitFor(s, Submit(s, MakeStubJob(s.root)), "successful");
  const std::string text = s.Client().Get("/metrics")->body;
  EXPECT_NE(text.find("satmesh_tiles_done_total 4"), std::string::npos) << text;
  EXPECT_NE(text.find("satmesh_queue_depth 0"), std::string::npos);
  EXPECT_NE(text.find("satmesh_tile_duration_seconds_count 4"), std::string::npos);
  EXPECT_NE(text.find("satmesh_jobs{status=\"successful\"} 1"), std::string::npos);
}

TEST(Api, TilesOfTwoJobsAlternate) {
  TestServer s("fair", Stub(4, 1, 100), /*workers=*/1);
  s.Start();
  auto c = s.Client();
  const std::string a = Submit(s, MakeStubJob(s.root)), b = Submit(s, MakeStubJob(s.root));
  int a_done_when_b_first = -1;
  for (int i = 0; i < 1000 && a_done_when_b_first < 0; ++i) {
    const json ia = Json(c.Get(("/jobs/" + a).c_str())), ib = Json(c.Get(("/jobs/" + b).c_str()));
    if (ib["tiles"]["done"] >= 1) a_done_when_b_first = ia["tiles"]["done"];
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_GE(a_done_when_b_first, 1);
  EXPECT_LE(a_done_when_b_first, 2);  // round robin: a0, b0, a1, b1, ...
  WaitFor(s, a, "successful");
  EXPECT_EQ(WaitFor(s, b, "successful")["status"], "successful");
}

TEST(Api, RestartResumesUnfinishedTilesOnce) {
  std::string id;
  {
    TestServer s("restart", Stub(4, 1, 200), 1);
    s.Start();
    id = Submit(s, MakeStubJob(s.root));
    for (int i = 0; i < 500; ++i) {
      if (Json(s.Client().Get(("/jobs/" + id).c_str()))["tiles"]["done"] >= 1) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    s.Stop();
  }
  TestServer again("restart", Stub(4, 1, 200), 1, "", /*fresh=*/false);
  again.Start();
  ASSERT_EQ(WaitFor(again, id, "successful")["status"], "successful");
  std::ifstream log(again.options.data_dir + "/jobs/" + id + "/completions.log");
  std::map<std::string, int> count;
  for (std::string line; std::getline(log, line);) ++count[line];
  EXPECT_EQ(count.size(), 4u);
  for (const auto& [tile, n] : count) EXPECT_EQ(n, 1) << tile;
}

}  // namespace
}  // namespace satmesh::server::testing
