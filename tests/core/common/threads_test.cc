#include "core/common/threads.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <thread>
#include <vector>

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

// Units of work run one per thread when every thread gets as many (or the remainder is
// small), else one after the other with the team inside each.
TEST(OnePerThread, WhenTheUnitsShareOutEvenly) {
  std::vector<int> one_per_thread;
  std::thread worker([&] {
    omp_set_num_threads(2);
    for (size_t items = 0; items <= 9; ++items) one_per_thread.push_back(OnePerThread(items));
  });
  worker.join();
  // 0 and 1 units leave a thread idle; 3, 5 and 7 a remainder; from 8 it is small.
  EXPECT_EQ(one_per_thread, (std::vector<int>{0, 0, 1, 0, 1, 0, 1, 0, 1, 1}));
}

}  // namespace
}  // namespace satmesh
