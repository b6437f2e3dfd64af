#pragma once
// A job's plan made once per job in this process. PlanJob reads the DSM header and the
// images' RPCs and, for a mesh job, reads, repairs and hole-fills the whole mesh: the
// tiles of one job (and its assembly) share one plan instead of making it each.
#include <cstddef>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "core/tiling/tile_plan.h"

namespace satmesh::server {

class PlanCache {
 public:
  explicit PlanCache(size_t capacity = 4) : capacity_(capacity) {}

  // The plan for `key` (a job's directory), made by `make` the first time; the least
  // recently used plan is dropped beyond the capacity (it stays alive while a tile holds
  // it). A failed `make` caches nothing and throws. Thread-safe; one plan is made at a
  // time (planning is seconds, a tile minutes).
  std::shared_ptr<const JobPlan> Get(const std::string& key, const std::function<JobPlan()>& make);

 private:
  std::mutex mutex_;
  size_t capacity_;
  std::list<std::pair<std::string, std::shared_ptr<const JobPlan>>> entries_;  // most recent first
};

}  // namespace satmesh::server
