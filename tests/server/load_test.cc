// 20 clients polling status while tiles run: every poll answers; latency is printed
// (p50/p99), not asserted.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>

#include "tests/server/test_server.h"

namespace satmesh::server::testing {
namespace {

TEST(Load, TwentyClientsPollWhileTilesRun) {
  TestServer s("load", Stub(4, 2, 250), /*workers=*/2);
  s.Start();
  const std::string id = Submit(s, MakeStubJob(s.root));
  ASSERT_FALSE(id.empty());
  constexpr int kClients = 20;
  std::vector<std::vector<double>> latency_ms(kClients);
  std::atomic<int> failures{0};
  std::atomic<bool> finished{false};
  std::vector<std::thread> threads;
  for (int i = 0; i < kClients; ++i) {
    threads.emplace_back([&, i] {
      auto c = s.Client();
      c.set_tcp_nodelay(true);
      c.set_keep_alive(true);  // a poller keeps its connection (httplib's client default is one per request)
      for (int n = 0; n < 2000 && !finished; ++n) {  // bounded
        const auto t0 = std::chrono::steady_clock::now();
        auto r = c.Get(("/jobs/" + id).c_str());
        latency_ms[i].push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
        if (!r || r->status != 200) { ++failures; continue; }
        if (Json(r)["status"] == "successful") finished = true;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    });
  }
  for (auto& t : threads) t.join();
  // All requests, and without each client's first (its TCP connect: httplib listens with
  // a backlog of 5, so a burst of 20 connects can wait for a 1 s SYN retry; clients that
  // open a connection per request see that too).
  std::vector<double> all, steady;
  for (const auto& v : latency_ms) {
    all.insert(all.end(), v.begin(), v.end());
    if (v.size() > 1) steady.insert(steady.end(), v.begin() + 1, v.end());
  }
  std::sort(all.begin(), all.end());
  std::sort(steady.begin(), steady.end());
  ASSERT_FALSE(steady.empty());
  const auto pct = [](const std::vector<double>& x, double p) { return x[std::min(x.size() - 1, size_t(p * double(x.size())))]; };
  std::printf("[ latency ] %d clients, %zu status requests while 8 tiles ran: p50 %.2f ms, p99 %.2f ms, max %.2f ms; "
              "after connect: p50 %.2f ms, p99 %.2f ms, max %.2f ms\n", kClients, all.size(), pct(all, 0.5),
              pct(all, 0.99), all.back(), pct(steady, 0.5), pct(steady, 0.99), steady.back());
  EXPECT_EQ(failures.load(), 0);
  EXPECT_TRUE(finished.load());
}

}  // namespace
}  // namespace satmesh::server::testing
