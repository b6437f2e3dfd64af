#include "core/common/threads.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
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

}  // namespace
}  // namespace satmesh
