// The Redis queue end to end (issue 22), on the fixture of redis_fixture.h: a multi-tile
// job through API nodes and workers equals the single-process run; cancellation through
// another API node; the throughput measurement (disabled).
#include "tests/server/redis_fixture.h"

namespace satmesh::server::testing {
namespace {

TEST_F(RedisQueue, MultiTileJobMatchesTheSingleProcessRun) {
  // With the job's biases estimated once (by the first worker), as in-process.
  // 4 x 4 tiles of 18 m, submitted through one API node and read through the other, three
  // workers (issue 22: two API nodes, three workers, a 16-tile job).
  const json job = MakeJob(/*iterations=*/3, /*aoi_size_m=*/72, /*estimate_bias=*/true);
  const Process& api = StartApi();
  const Process& other_api = StartApi();
  StartWorker();
  StartWorker();
  StartWorker();
  const auto t0 = Clock::now();
  const std::string id = Submit(api, job);
  ASSERT_FALSE(id.empty());
  const json info = WaitEnd(api, id);
  const double queued_s = std::chrono::duration<double>(Clock::now() - t0).count();
  ASSERT_EQ(info["status"], "successful") << info.dump();
  auto c = Client(other_api);
  const json results = Json(c.Get(("/jobs/" + id + "/results").c_str()));
  const json served = results["metrics"]["value"];
  ExpectEveryTileOnce(Json(c.Get(("/jobs/" + id + "/tiles").c_str()))["tiles"], served, 16);
  EXPECT_EQ(c.Get(("/jobs/" + id + "/results/mesh.ply").c_str())->status, 200);
  EXPECT_EQ(c.Get(("/jobs/" + id + "/tiles/0_0.glb").c_str())->status, 200);
  auto submitter = Client(api);
  const std::string metrics_text = submitter.Get("/metrics")->body;
  EXPECT_NE(metrics_text.find("satmesh_workers_seen 3"), std::string::npos) << metrics_text;
  EXPECT_NE(metrics_text.find("satmesh_tiles_done_total 16"), std::string::npos) << metrics_text;
  EXPECT_EQ(Json(c.Get("/health"))["workers"], 3);

  const auto t1 = Clock::now();
  const JobOutputs local = RunJob(proto::JobSpecFromJson(job, scene_), dir_ + "/local");
  const double local_s = std::chrono::duration<double>(Clock::now() - t1).count();
  const json expected = proto::JobMetricsToJson(local);
  ASSERT_EQ(served["tiles"].size(), expected["tiles"].size());
  for (size_t t = 0; t < expected["tiles"].size(); ++t) {
    const json& a = served["tiles"][t];
    const json& b = expected["tiles"][t];
    EXPECT_EQ(a["name"], b["name"]);
    EXPECT_EQ(a["faces"], b["faces"]);
    EXPECT_EQ(a["vertices"], b["vertices"]);
    for (int k = 0; k < 6; ++k)  // radians, then metres (summation order: see below)
      EXPECT_NEAR(a["region"][k].get<double>(), b["region"][k].get<double>(), k < 4 ? 1e-9 : 1e-3) << a["name"];
    ASSERT_EQ(a.value("bias_px", json()).size(), b.value("bias_px", json()).size()) << a["name"];
    for (size_t v = 0; v < b.value("bias_px", json()).size(); ++v)
      for (int k = 0; k < 2; ++k)
        EXPECT_NEAR(a["bias_px"][v][k].get<double>(), b["bias_px"][v][k].get<double>(), 1e-3);
  }
  EXPECT_FALSE(local.job_bias_px.empty());
  EXPECT_EQ(served["totals"]["faces"], expected["totals"]["faces"]);
  EXPECT_EQ(served["totals"]["vertices"], expected["totals"]["vertices"]);
  EXPECT_EQ(served["seams_total"]["cells"], expected["seams_total"]["cells"]);
  for (const char* key : {"median_abs_m", "p95_abs_m", "max_abs_m", "mean_m"})
    EXPECT_NEAR(served["seams_total"][key].get<double>(), expected["seams_total"][key].get<double>(), 1e-3) << key;
  // The assembled mesh: the same faces, vertices within 1 cm (1/30 GSD): a worker runs
  // one thread, the in-process run two, so the per-vertex sums are added in another order,
  // and float rounding grows over the iterations (CI measured 2.0 mm on this 16-tile job;
  // session 21, with the remeshing's own relaxation: 0.04 mm in some runs, 5.38 mm in
  // others, where a pixel's hit face flips between the two orders and its vertex follows).
  std::ofstream(dir_ + "/served.ply", std::ios::binary) << c.Get(("/jobs/" + id + "/results/mesh.ply").c_str())->body;
  const TriangleMesh a = ReadMesh(dir_ + "/served.ply"), b = ReadMesh(local.mesh_path);
  ASSERT_EQ(a.faces, b.faces);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  double max_diff = 0;
  for (size_t v = 0; v < a.vertices.size(); ++v)
    max_diff = std::max(max_diff, (a.AbsoluteVertex(v) - b.AbsoluteVertex(v)).cwiseAbs().maxCoeff());
  EXPECT_LT(max_diff, 1e-2);
  std::printf("[ redis ] 16 tiles, 2 API nodes, 3 workers: submit->successful %.1f s; in-process (1 worker) %.1f s; "
              "largest vertex difference %.2f mm\n",
              queued_s, local_s, 1e3 * max_diff);
}

// The tiles must still be running when the job is dismissed: at 40 iterations a level a
// tiny tile finished in 0.5 s, and under CI's load the dismissal once came after two had
// written their results (session 35); 400 keep them busy for seconds, and a cancelled
// tile stops between iterations.
TEST_F(RedisQueue, CancellingThroughAnotherApiNodeStopsTheTiles) {
  const json job = MakeJob(/*iterations=*/400);
  const Process& api = StartApi();
  const Process& other = StartApi();
  StartWorker();
  StartWorker();
  const std::string id = Submit(api, job);
  ASSERT_FALSE(id.empty());
  RedisConnection redis(ParseRedisUrl(url_));
  const std::string live = "satmesh:job:" + id + ":live";
  for (int i = 0; i < 600 && redis.Command({"HLEN", live}).integer < 2; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_EQ(redis.Command({"HLEN", live}).integer, 2) << "two tiles should run on the two workers";
  // Any API node answers for any job.
  EXPECT_EQ(Json(Client(other).Get(("/jobs/" + id).c_str()))["status"], "running");
  const auto t0 = Clock::now();
  auto r = Client(other).Delete(("/jobs/" + id).c_str());
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(Json(r)["status"], "dismissed");
  while (Clock::now() - t0 < std::chrono::seconds(10) &&
         (redis.Command({"HLEN", live}).integer > 0 ||
          redis.Command({"XPENDING", "satmesh:tiles", "workers"}).elements.at(0).integer > 0))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  const double stop_s = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(redis.Command({"HLEN", live}).integer, 0);
  EXPECT_LT(stop_s, 5.0) << "the running tiles did not stop within seconds";
  EXPECT_EQ(Json(Client(api).Get(("/jobs/" + id).c_str()))["status"], "dismissed");
  // Queued tiles are not started afterwards either; no tile has a result.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  EXPECT_EQ(redis.Command({"HLEN", live}).integer, 0);
  EXPECT_EQ(redis.Command({"HLEN", "satmesh:job:" + id + ":results"}).integer, 0);
  std::printf("[ redis ] dismissed through the other API node; running tiles stopped in %.2f s\n", stop_s);
}

// Acknowledged tiles leave the stream (XTRIM MINID after each XACK): it holds only queued
// and running tiles, and is empty after each job; the group's lag stays defined.
TEST_F(RedisQueue, AcknowledgedTilesLeaveTheStream) {
  const json job = MakeJob(/*iterations=*/1);
  const Process& api = StartApi();
  StartWorker();
  StartWorker();
  RedisConnection redis(ParseRedisUrl(url_));
  const auto stream_info = [&] {  // XINFO STREAM as a map of its integer fields
    std::map<std::string, long long> out;
    const RedisReply r = redis.Command({"XINFO", "STREAM", "satmesh:tiles"});
    for (size_t i = 0; i + 1 < r.elements.size(); i += 2) out[r.elements[i].str] = r.elements[i + 1].integer;
    return out;
  };
  const auto group_lag = [&]() -> std::optional<long long> {
    const RedisReply groups = redis.Command({"XINFO", "GROUPS", "satmesh:tiles"});
    const auto& g = groups.elements.at(0).elements;
    for (size_t i = 0; i + 1 < g.size(); i += 2)
      if (g[i].str == "lag") return g[i + 1].nil() ? std::nullopt : std::optional(g[i + 1].integer);
    return std::nullopt;
  };
  for (int round = 1; round <= 2; ++round) {
    const std::string id = Submit(api, job);
    ASSERT_FALSE(id.empty());
    long long max_length = 0;
    json info;
    const auto until = Clock::now() + std::chrono::seconds(300);
    do {  // the length while the job runs, sampled every 20 ms
      max_length = std::max(max_length, redis.Command({"XLEN", "satmesh:tiles"}).integer);
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      info = Json(Client(api).Get(("/jobs/" + id).c_str()));
    } while ((info["status"] == "accepted" || info["status"] == "running") && Clock::now() < until);
    ASSERT_EQ(info["status"], "successful") << info.dump();
    // The last tile's worker acknowledges after the job ends: wait for that XACK.
    for (int i = 0; i < 100 && stream_info()["length"] > 0; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const auto after = stream_info();
    EXPECT_EQ(after.at("length"), 0) << "round " << round;
    EXPECT_EQ(after.at("entries-added"), 4 * round);
    EXPECT_LE(max_length, 4);
    EXPECT_EQ(redis.Command({"XPENDING", "satmesh:tiles", "workers"}).elements.at(0).integer, 0);
    EXPECT_EQ(group_lag(), std::optional<long long>(0)) << "the group's lag must stay defined";
    std::printf("[ redis ] job %d: 4 tiles; stream length at most %lld while it ran, %lld after\n", round,
                max_length, after.at("length"));
  }
}

// Throughput (not run by ctest: a measurement; run it alone, under
// flock /tmp/satmesh-bench.lock): the 16-tile job with 1, 2 and 3 workers, tiles per
// minute, and Redis's load per tile (commands, bytes in and out) for the model of N machines.
TEST_F(RedisQueue, DISABLED_ThroughputWithOneTwoThreeWorkers) {
  const json job = MakeJob(/*iterations=*/3, /*aoi_size_m=*/72);
  const Process& api = StartApi();
  RedisConnection redis(ParseRedisUrl(url_));
  const auto stat = [&](const std::string& key) {
    const std::string info = redis.Command({"INFO", "stats"}).str;
    const size_t at = info.find(key + ":");
    return at == std::string::npos ? 0.0 : std::atof(info.c_str() + at + key.size() + 1);
  };
  for (int n = 1; n <= 3; ++n) {
    while (!workers_.empty()) {
      workers_.back().Kill(SIGTERM);
      workers_.pop_back();
    }
    for (int i = 0; i < n; ++i) StartWorker();
    std::this_thread::sleep_for(std::chrono::seconds(1));
    const double commands0 = stat("total_commands_processed"), in0 = stat("total_net_input_bytes"),
                 out0 = stat("total_net_output_bytes");
    const auto t0 = Clock::now();
    const std::string id = Submit(api, job);
    const json info = WaitEnd(api, id);
    const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
    ASSERT_EQ(info["status"], "successful") << info.dump();
    // Less the polling of this test and the idle workers' reads (about 1/s each).
    const double commands = stat("total_commands_processed") - commands0, in = stat("total_net_input_bytes") - in0,
                 out = stat("total_net_output_bytes") - out0;
    std::printf("[ redis ] %d worker(s): 16 tiles in %.1f s = %.1f tiles/min; Redis per tile (with this test's "
                "polling): %.0f commands, %.1f kB in, %.1f kB out\n",
                n, wall_s, 16 * 60 / wall_s, commands / 16, in / 16 / 1024, out / 16 / 1024);
  }
}

}  // namespace
}  // namespace satmesh::server::testing
