// The Redis queue's options and URLs (issue 22): no redis-server needed.
#include "tests/server/redis_fixture.h"

namespace satmesh::server::testing {
namespace {

TEST(RedisUrl, ParsesHostPortAndDbAndRefusesOthers) {
  const RedisAddress a = ParseRedisUrl("redis://10.0.0.5:6380/2");
  EXPECT_EQ(a.host, "10.0.0.5");
  EXPECT_EQ(a.port, 6380);
  EXPECT_EQ(a.db, 2);
  const RedisAddress b = ParseRedisUrl("redis://redis");
  EXPECT_EQ(b.host, "redis");
  EXPECT_EQ(b.port, 6379);
  EXPECT_EQ(b.db, 0);
  for (const char* bad : {"http://x:1", "redis://", "redis://h:0", "redis://h:x", "redis://h:1/db"})
    EXPECT_THROW(ParseRedisUrl(bad), Error) << bad;
}

TEST(RedisQueueOptions, DefaultsAreValidAndBadValuesNamed) {
  RedisQueueOptions o;
  o.url = "redis://127.0.0.1:6379";
  EXPECT_EQ(o.Check(), "");
  RedisQueueOptions bad = o;
  bad.idle_timeout_s = 0.1;
  EXPECT_NE(bad.Check().find("--idle-timeout-s must be in [0.5, 86400], got 0.1"), std::string::npos) << bad.Check();
  bad = o;
  bad.max_deliveries = 0;
  EXPECT_NE(bad.Check().find("--max-deliveries must be >= 1, got 0"), std::string::npos) << bad.Check();
  RedisWorkerOptions w;
  w.queue = o;
  EXPECT_NE(w.Check().find("data_dir"), std::string::npos);
  w.data_dir = "/data";
  EXPECT_EQ(w.Check(), "");
  // satmesh-server --queue: a bad URL is refused naming it.
  EXPECT_THROW(ParseServerArgs({"--queue", "redis://"}), Error);
  const ServerOptions parsed = ParseServerArgs({"--queue", "redis://r:1/3", "--queue-prefix", "city"});
  EXPECT_EQ(parsed.queue, "redis://r:1/3");
  EXPECT_EQ(parsed.redis.prefix, "city");
  EXPECT_THROW(ParseServerArgs({"--queue", "redis://r:1", "--queue-prefix", ""}), Error);
}

TEST(RedisWorkerArgs, ParsedFromTheTableAndBadValuesNamed) {
  const RedisWorkerOptions o = ParseRedisWorkerArgs(
      {"--queue", "redis://r:7/1", "--data-dir", "/data", "--threads", "3", "--memory-budget", "512.5",
       "--idle-timeout-s", "2.5", "--max-deliveries", "5", "--prefix", "city", "--name", "w"});
  EXPECT_EQ(o.queue.url, "redis://r:7/1");
  EXPECT_EQ(o.data_dir, "/data");
  EXPECT_EQ(o.threads, 3);
  EXPECT_DOUBLE_EQ(o.memory_budget_mb, 512.5);
  EXPECT_DOUBLE_EQ(o.MemoryBudgetMb(), 512.5);
  EXPECT_DOUBLE_EQ(o.queue.idle_timeout_s, 2.5);
  EXPECT_EQ(o.queue.max_deliveries, 5);
  EXPECT_EQ(o.queue.prefix, "city");
  EXPECT_EQ(o.name, "w");
  // Defaults: the table's (the fields' initializers); the budget a quarter of this machine's
  // memory over the threads.
  const RedisWorkerOptions d = ParseRedisWorkerArgs({"--queue", "redis://r", "--data-dir", "/d", "--threads", "4"});
  EXPECT_EQ(d.memory_budget_mb, 0);
  EXPECT_EQ(d.queue.max_deliveries, 3);
  EXPECT_DOUBLE_EQ(d.queue.idle_timeout_s, 30);
  const double physical_mb = double(sysconf(_SC_PHYS_PAGES)) * double(sysconf(_SC_PAGE_SIZE)) / (1 << 20);
  EXPECT_NEAR(d.MemoryBudgetMb(), physical_mb / 16, 1e-6);
  EXPECT_GT(d.MemoryBudgetMb(), 16);  // any machine that runs the tests
  const auto message = [](const std::vector<std::string>& extra) {
    std::vector<std::string> args = {"--queue", "redis://r", "--data-dir", "/d"};
    args.insert(args.end(), extra.begin(), extra.end());
    try {
      ParseRedisWorkerArgs(args);
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(message({"--memory-budget", "-1"}).find("--memory-budget must be >= 0, got -1"), std::string::npos);
  EXPECT_NE(message({"--memory-budget", "lots"}).find("--memory-budget: expected a number, got 'lots'"),
            std::string::npos);
  EXPECT_NE(message({"--threads", "1.5"}).find("--threads: expected an integer, got '1.5'"), std::string::npos);
  EXPECT_NE(message({"--threads", "0"}).find("--threads must be in [1, 256], got 0"), std::string::npos);
  EXPECT_NE(message({"--colour", "red"}).find("unknown option --colour"), std::string::npos);
  EXPECT_NE(message({"--threads"}).find("unexpected argument '--threads'"), std::string::npos);
  // The usage lists every option of the table once.
  const std::string usage = RedisWorkerUsage();
  for (const auto& option : RedisWorkerOptionTable())
    EXPECT_NE(usage.find("[--" + std::string(option.name) + " "), std::string::npos) << option.name;
  EXPECT_NE(usage.find("[--memory-budget 0]"), std::string::npos) << usage;
}

}  // namespace
}  // namespace satmesh::server::testing
