// satmesh-worker's memory budget (issue 22), on the fixture of redis_fixture.h: before a
// tile starts, the plan's estimate of its peak is compared with the worker's own
// --memory-budget; a tile that cannot fit fails unstarted, its record naming the budget
// and the need, and a worker with room refines the same job.
#include <cstdlib>
#include <regex>

#include "tests/server/redis_fixture.h"

namespace satmesh::server::testing {
namespace {

// The numbers of "tile X needs an estimated N MB (...) but the memory budget is B MB".
std::pair<double, double> NeedAndBudget(const std::string& message) {
  std::smatch m;
  if (!std::regex_search(message, m, std::regex(R"(needs an estimated (\d+) MB .* memory budget is (\d+) MB)")))
    return {-1, -1};
  return {std::atof(m[1].str().c_str()), std::atof(m[2].str().c_str())};
}

TEST_F(RedisQueue, ATileOverTheWorkersMemoryBudgetFailsUnstartedNamingBudgetAndNeed) {
  const json job = MakeJob(/*iterations=*/3);
  const Process& api = StartApi();
  // 100 MB: below the model's fixed part (kBaseMb, 150 MB), so no tile fits.
  StartWorker(/*idle_timeout_s=*/30, /*max_deliveries=*/3, {"--memory-budget", "100"});
  const auto t0 = Clock::now();
  const std::string id = Submit(api, job);
  ASSERT_FALSE(id.empty());
  const json info = WaitEnd(api, id, /*timeout_s=*/60);
  const double wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  ASSERT_EQ(info["status"], "failed") << info.dump();
  const json tiles = Json(Client(api).Get(("/jobs/" + id + "/tiles").c_str()))["tiles"];
  ASSERT_EQ(tiles.size(), 4u);
  for (const json& t : tiles) {
    EXPECT_EQ(t["status"], "failed") << t.dump();
    EXPECT_EQ(t["attempts"], 1) << t.dump();  // failed once, not retried as a dead worker's
    const std::string message = t.value("message", "");
    const auto [need_mb, budget_mb] = NeedAndBudget(message);
    EXPECT_EQ(budget_mb, 100) << message;
    EXPECT_GE(need_mb, 150) << message;  // the fixed part alone
    EXPECT_LT(need_mb, 400) << message;  // a 24 m tile of the tiny scene
    EXPECT_NE(message.find("per worker (this worker's --memory-budget)"), std::string::npos) << message;
  }
  // Refused, not refined: no tile file, and far quicker than one refinement.
  EXPECT_FALSE(fs::exists(data_ + "/jobs/" + id + "/tiles/0_0.glb"));
  EXPECT_LT(wall_s, 20);
  std::printf("[ redis ] 4 tiles over a 100 MB worker budget failed unstarted in %.1f s: %s\n", wall_s,
              tiles[0].value("message", "").c_str());
}

TEST_F(RedisQueue, AWorkerWithRoomRefinesWhatFitsItsBudget) {
  const json job = MakeJob(/*iterations=*/1);
  const Process& api = StartApi();
  StartWorker(/*idle_timeout_s=*/30, /*max_deliveries=*/3, {"--memory-budget", "2000"});
  const std::string id = Submit(api, job);
  ASSERT_FALSE(id.empty());
  const json info = WaitEnd(api, id);
  ASSERT_EQ(info["status"], "successful") << info.dump();
  const json tiles = Json(Client(api).Get(("/jobs/" + id + "/tiles").c_str()))["tiles"];
  ASSERT_EQ(tiles.size(), 4u);
  for (const json& t : tiles) EXPECT_EQ(t["status"], "done") << t.dump();
  // The log names the budget it runs under.
  std::ifstream log(dir_ + "/w0.log");
  const std::string text(std::istreambuf_iterator<char>(log), {});
  EXPECT_NE(text.find("memory budget 2000 MB per thread"), std::string::npos) << text;
}

}  // namespace
}  // namespace satmesh::server::testing
