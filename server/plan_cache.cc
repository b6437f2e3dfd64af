#include "server/plan_cache.h"

namespace satmesh::server {

std::shared_ptr<const JobPlan> PlanCache::Get(const std::string& key,
                                              const std::function<JobPlan()>& make) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto it = entries_.begin(); it != entries_.end(); ++it) {
    if (it->first != key) continue;
    entries_.splice(entries_.begin(), entries_, it);
    return entries_.front().second;
  }
  auto plan = std::make_shared<const JobPlan>(make());
  entries_.emplace_front(key, plan);
  while (entries_.size() > capacity_) entries_.pop_back();
  return plan;
}

}  // namespace satmesh::server
