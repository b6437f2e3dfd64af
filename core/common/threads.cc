#include "core/common/threads.h"

#include <omp.h>

#include <algorithm>
#include <exception>
#include <thread>

namespace satmesh {

int ShareProcessorsAmongWorkers(int workers) {
  const int threads = std::max(1, omp_get_num_procs() / std::max(1, workers));
  omp_set_num_threads(threads);
  return threads;
}

void RunAlongside(const std::function<void()>& side, const std::function<void()>& main) {
  const int threads = omp_get_max_threads();
  std::exception_ptr side_failure, main_failure;
  std::thread helper([&] {
    omp_set_num_threads(threads);
    try {
      side();
    } catch (...) {
      side_failure = std::current_exception();
    }
  });
  try {
    main();
  } catch (...) {
    main_failure = std::current_exception();
  }
  helper.join();
  if (main_failure) std::rethrow_exception(main_failure);
  if (side_failure) std::rethrow_exception(side_failure);
}

}  // namespace satmesh
