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
  EXPECT_NE(bad.Check().find("idle_timeout_s"), std::string::npos);
  bad = o;
  bad.max_deliveries = 0;
  EXPECT_NE(bad.Check().find("max_deliveries"), std::string::npos);
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

}  // namespace
}  // namespace satmesh::server::testing
