// The HTTP API over loopback with the stub engine (no refinement).
#include <gtest/gtest.h>

#include <fstream>

#include "core/mesh/mesh_io.h"
#include "core/tiling/memory_budget.h"
#include "proto/job_spec_json.h"
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
  // The refinement and tiling options as declared once (RefineOptionTable,
  // TilingOptionTable): type, default, range, help.
  EXPECT_EQ(d["inputs"]["job"]["schema"]["properties"]["options"]["properties"], proto::RefineOptionsSchema());
  EXPECT_EQ(d["inputs"]["job"]["schema"]["properties"]["tiling"]["properties"], proto::TilingOptionsSchema());
  EXPECT_EQ(Json(c.Get("/api"))["openapi"], "3.0.3");
  EXPECT_EQ(Json(c.Get("/health"))["status"], "ok");
  // Links are absolute, from the request's Host (OWSLib follows them as they are).
  const std::string base = "http://127.0.0.1:" + std::to_string(s.port);
  // (a named copy: a range-for over Json(...)["links"] iterates a destroyed temporary,
  // found by the ASan build)
  const json landing = Json(c.Get("/"));
  for (const auto& link : landing["links"]) EXPECT_EQ(link["href"].get<std::string>().rfind(base + "/", 0), 0u) << link;
  EXPECT_EQ(Json(c.Get("/processes/refine-mesh"))["links"][0]["href"], base + "/processes/refine-mesh");
}

TEST(Api, CorsPreflightAndHeadersForAllowedOriginsOnly) {
  TestServer s("cors", {}, 2, "secret");
  s.options.cors_origins = {"https://viewer.example"};
  s.Start();
  auto c = s.Client();
  // A browser's preflight carries no credentials: answered before authentication.
  const httplib::Headers preflight = {{"Origin", "https://viewer.example"},
                                      {"Access-Control-Request-Method", "GET"},
                                      {"Access-Control-Request-Headers", "authorization"}};
  auto r = c.Options("/jobs/abc/tileset.json", preflight);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 204);
  EXPECT_EQ(r->get_header_value("Access-Control-Allow-Origin"), "https://viewer.example");
  EXPECT_NE(r->get_header_value("Access-Control-Allow-Headers").find("Authorization"), std::string::npos);
  EXPECT_EQ(r->get_header_value("Access-Control-Allow-Methods"), "GET, HEAD, OPTIONS");
  r = c.Options("/processes/refine-mesh/execution", preflight);
  EXPECT_EQ(r->get_header_value("Access-Control-Allow-Methods"), "POST, OPTIONS");
  // The real request: the origin is echoed (Vary: Origin), also on a 401.
  r = c.Get("/jobs", {{"Origin", "https://viewer.example"}, {"Authorization", "Bearer secret"}});
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Access-Control-Allow-Origin"), "https://viewer.example");
  EXPECT_EQ(r->get_header_value("Vary"), "Origin");
  r = c.Get("/jobs", {{"Origin", "https://viewer.example"}});
  EXPECT_EQ(r->status, 401);
  EXPECT_EQ(r->get_header_value("Access-Control-Allow-Origin"), "https://viewer.example");
  // Another origin gets no CORS headers, its preflight no Allow-Methods.
  r = c.Get("/jobs", {{"Origin", "https://other.example"}, {"Authorization", "Bearer secret"}});
  EXPECT_EQ(r->status, 200);
  EXPECT_FALSE(r->has_header("Access-Control-Allow-Origin"));
  r = c.Options("/jobs", {{"Origin", "https://other.example"}, {"Access-Control-Request-Method", "GET"}});
  EXPECT_FALSE(r->has_header("Access-Control-Allow-Origin"));
  EXPECT_FALSE(r->has_header("Access-Control-Allow-Methods"));
}

TEST(Api, NoCorsHeadersByDefaultAndAnyOriginWithStar) {
  TestServer plain("cors_none");
  plain.Start();
  auto r = plain.Client().Get("/processes", {{"Origin", "https://viewer.example"}});
  EXPECT_EQ(r->status, 200);
  EXPECT_FALSE(r->has_header("Access-Control-Allow-Origin"));
  TestServer any("cors_any");
  any.options.cors_origins = {"*"};
  any.Start();
  r = any.Client().Get("/processes", {{"Origin", "https://viewer.example"}});
  EXPECT_EQ(r->get_header_value("Access-Control-Allow-Origin"), "*");
}

TEST(Api, BadCorsOriginRejectedByName) {
  ServerOptions o;
  o.cors_origins = {"viewer.example"};
  EXPECT_NE(o.Check().find("cors_origins: 'viewer.example'"), std::string::npos) << o.Check();
  o.cors_origins = {"https://viewer.example/app"};
  EXPECT_NE(o.Check().find("cors_origins"), std::string::npos);
  o.cors_origins = {"https://viewer.example:8443", "*"};
  EXPECT_EQ(o.Check(), "");
}

TEST(Api, WrongMethodIs405WithAllow) {
  TestServer s("methods");
  s.Start();
  auto c = s.Client();
  auto r = c.Put("/jobs", "{}", "application/json");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 405);
  EXPECT_EQ(r->get_header_value("Allow"), "GET, HEAD, OPTIONS");
  EXPECT_EQ(r->get_header_value("Content-Type"), "application/problem+json");
  EXPECT_NE(Json(r)["type"].get<std::string>().find("method-not-allowed"), std::string::npos);
  r = c.Post("/jobs/abc", "{}", "application/json");
  EXPECT_EQ(r->status, 405);
  EXPECT_EQ(r->get_header_value("Allow"), "GET, HEAD, DELETE, OPTIONS");
  r = c.Get("/processes/refine-mesh/execution");
  EXPECT_EQ(r->status, 405);
  EXPECT_EQ(r->get_header_value("Allow"), "POST, OPTIONS");
  r = c.Delete("/processes");
  EXPECT_EQ(r->status, 405);
  r = c.Options("/jobs/abc");
  EXPECT_EQ(r->status, 204);
  EXPECT_EQ(r->get_header_value("Allow"), "GET, HEAD, DELETE, OPTIONS");
  EXPECT_EQ(c.Put("/no/such/route", "{}", "application/json")->status, 404);
}

TEST(Api, ExecuteTakesTheDescribedJobInputAndTheOlderForms) {
  TestServer s("inputs_job");
  s.Start();
  auto c = s.Client();
  const json job = MakeStubJob(s.root);
  for (const json& body : {json{{"inputs", {{"job", job}}}}, json{{"inputs", job}}, job}) {
    auto r = c.Post("/processes/refine-mesh/execution", body.dump(), "application/json");
    ASSERT_EQ(r->status, 201) << body.dump() << " -> " << r->body;
    EXPECT_EQ(WaitFor(s, Json(r)["jobID"], "successful")["status"], "successful");
  }
  auto r = c.Post("/processes/refine-mesh/execution", json{{"inputs", {{"job", "images.json"}}}}.dump(),
                  "application/json");
  EXPECT_EQ(r->status, 400);
  EXPECT_NE(Json(r)["detail"].get<std::string>().find("inputs.job"), std::string::npos) << r->body;
  // The description declares exactly that input.
  const json d = Json(c.Get("/processes/refine-mesh"));
  EXPECT_EQ(d["inputs"].size(), 1u);
  EXPECT_TRUE(d["inputs"].contains("job"));
}

TEST(Api, ViewerPageAndCesiumServedWithoutTokenJobDataWithIt) {
  TestServer s("viewer", {}, 2, "secret");
  s.Start();
  auto c = s.Client();
  const httplib::Headers auth = {{"Authorization", "Bearer secret"}};
  auto r = c.Post("/processes/refine-mesh/execution", auth, MakeStubJob(s.root).dump(), "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string id = Json(r)["jobID"];
  r = c.Get(("/jobs/" + id + "/viewer").c_str());
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(r->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_NE(r->body.find("Cesium.js"), std::string::npos);
  r = c.Get("/viewer/Cesium/Cesium.js");
  EXPECT_EQ(r->status, 200);
  EXPECT_GT(r->body.size(), 1000000u);  // the minified CesiumJS, ~4 MB
  EXPECT_EQ(c.Get(("/jobs/" + id + "/tileset.json").c_str())->status, 401);
  r = c.Get(("/jobs/" + id + "/tileset.json").c_str(), auth);
  EXPECT_EQ(r->status, 200);
  EXPECT_EQ(Json(r)["extras"]["tiles_total"], 4);
  EXPECT_EQ(c.Get("/jobs/nosuchjob/viewer")->status, 404);
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

// The failure policy of core/tiling/job.h: a failing tile fails that tile, the job's other
// tiles go on and the job is assembled from them; it fails only when every tile failed.
TEST(Api, FailingTileFailsOnlyThatTile) {
  TestServer s("fail", Stub(3, 1, 10, "1_0"));
  s.Start();
  auto c = s.Client();
  const std::string id = Submit(s, MakeStubJob(s.root));
  const json info = WaitFor(s, id, "successful");
  ASSERT_EQ(info["status"], "successful") << info.dump();
  EXPECT_NE(info["message"].get<std::string>().find("1 of 3 tiles failed"), std::string::npos) << info.dump();
  EXPECT_NE(info["message"].get<std::string>().find("tile 1_0"), std::string::npos) << info.dump();
  const json tiles = Json(c.Get(("/jobs/" + id + "/tiles").c_str()))["tiles"];
  ASSERT_EQ(tiles.size(), 3u);
  for (const auto& t : tiles) {
    const bool failing = t["x"] == 1;
    EXPECT_EQ(t["status"], failing ? "failed" : "done") << t.dump();
    if (failing) {
      EXPECT_NE(t["message"].get<std::string>().find("stub: tile 1_0 fails"), std::string::npos);
    }
  }
  EXPECT_EQ(c.Get(("/jobs/" + id + "/results").c_str())->status, 200);
  EXPECT_EQ(c.Get(("/jobs/" + id + "/tiles/0_0.glb").c_str())->status, 200);
  EXPECT_EQ(c.Get(("/jobs/" + id + "/tiles/1_0.glb").c_str())->status, 404);
  const json metrics = Json(c.Get(("/jobs/" + id + "/results/metrics.json").c_str()));
  EXPECT_EQ(metrics["tiles"], 2);
}

TEST(Api, JobFailsWhenEveryTileFailed) {
  TestServer s("fail_all", Stub(1, 1, 10, "0_0"));
  s.Start();
  const std::string id = Submit(s, MakeStubJob(s.root));
  const json info = WaitFor(s, id, "failed");
  ASSERT_EQ(info["status"], "failed");
  EXPECT_NE(info["message"].get<std::string>().find("tile 0_0"), std::string::npos) << info.dump();
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
