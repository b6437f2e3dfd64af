#include "core/common/threads.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <stdexcept>
#include <thread>

namespace satmesh {
namespace {

// Each worker thread gets its share of the processors; the thread that started the
// workers keeps its own setting.
TEST(ShareProcessorsAmongWorkers, SplitsTheProcessorsPerWorkerThread) {
  const int procs = omp_get_num_procs();
  const int before = omp_get_max_threads();
  int in_worker = 0, in_region = 0, returned = 0;
  std::thread worker([&] {
    returned = ShareProcessorsAmongWorkers(2);
    in_worker = omp_get_max_threads();
#pragma omp parallel
#pragma omp single
    in_region = omp_get_num_threads();
  });
  worker.join();
  EXPECT_EQ(returned, std::max(1, procs / 2));
  EXPECT_EQ(in_worker, returned);
  EXPECT_EQ(in_region, returned);  // the worker's parallel regions use its share
  EXPECT_EQ(omp_get_max_threads(), before);
}

TEST(ShareProcessorsAmongWorkers, NeverBelowOneThread) {
  int returned = 0;
  std::thread worker([&] { returned = ShareProcessorsAmongWorkers(100000); });
  worker.join();
  EXPECT_EQ(returned, 1);
}

// The side function runs on another thread, with the caller's (a worker's) number of
// OpenMP threads, and both have run when RunAlongside returns.
TEST(RunAlongside, RunsBothTheSideOnAThreadOfItsOwnWithTheCallersTeam) {
  std::thread::id side_id, main_id;
  int side_team = 0, worker_team = 0;
  std::thread worker([&] {
    worker_team = ShareProcessorsAmongWorkers(omp_get_num_procs());  // 1 thread
    RunAlongside([&] { side_id = std::this_thread::get_id(), side_team = omp_get_max_threads(); },
                 [&] { main_id = std::this_thread::get_id(); });
    EXPECT_EQ(main_id, std::this_thread::get_id());
  });
  worker.join();
  EXPECT_NE(side_id, std::thread::id());
  EXPECT_NE(side_id, main_id);
  EXPECT_EQ(worker_team, 1);
  EXPECT_EQ(side_team, 1);
}

// A failure of either is rethrown after both returned; main's first when both fail.
TEST(RunAlongside, RethrowsAFailureAfterBothReturned) {
  bool main_ran = false, side_ran = false;
  try {
    RunAlongside([] { throw std::runtime_error("side"); }, [&] { main_ran = true; });
    ADD_FAILURE() << "the side's failure was not rethrown";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "side");
  }
  EXPECT_TRUE(main_ran);
  try {
    RunAlongside([&] { side_ran = true; }, [] { throw std::runtime_error("main"); });
    ADD_FAILURE() << "main's failure was not rethrown";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "main");
  }
  EXPECT_TRUE(side_ran);
  try {
    RunAlongside([] { throw std::runtime_error("side"); }, [] { throw std::runtime_error("main"); });
    ADD_FAILURE() << "no failure rethrown";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "main");
  }
}

}  // namespace
}  // namespace satmesh
