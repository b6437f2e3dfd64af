#include "core/common/threads.h"

#include <omp.h>

#include <algorithm>

namespace satmesh {

int ShareProcessorsAmongWorkers(int workers) {
  const int threads = std::max(1, omp_get_num_procs() / std::max(1, workers));
  omp_set_num_threads(threads);
  return threads;
}

}  // namespace satmesh
