#include "core/common/threads.h"

#include <omp.h>

#include <algorithm>

namespace satmesh {

int ShareProcessorsAmongWorkers(int workers) {
  const int threads = std::max(1, omp_get_num_procs() / std::max(1, workers));
  omp_set_num_threads(threads);
  return threads;
}

bool OnePerThread(size_t items) {
  const size_t threads = size_t(std::max(1, omp_get_max_threads()));
  return items >= threads && (items % threads == 0 || items >= 4 * threads);
}

}  // namespace satmesh
