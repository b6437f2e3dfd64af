#include "core/refine/pairs.h"

#include <algorithm>
#include <cmath>

namespace satmesh {

double IntersectionAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

std::vector<std::pair<int, int>> SelectPairs(const std::vector<PairCandidateView>& views,
                                             const PairOptions& options) {
  struct Candidate {
    int i, j;
    double score;  // distance from the middle of the angle range (smaller is better)
  };
  const double mid = 0.5 * (options.min_angle_deg + options.max_angle_deg);
  std::vector<Candidate> candidates;
  for (int i = 0; i < int(views.size()); ++i) {
    if (views[i].contrast < options.min_contrast) continue;
    for (int j = i + 1; j < int(views.size()); ++j) {
      if (views[j].contrast < options.min_contrast) continue;
      const double angle = IntersectionAngleDeg(views[i].direction, views[j].direction);
      if (angle < options.min_angle_deg || angle > options.max_angle_deg) continue;
      candidates.push_back({i, j, std::abs(angle - mid)});
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
  std::vector<int> count(views.size(), 0);
  std::vector<std::pair<int, int>> pairs;
  for (const auto& c : candidates) {
    if (count[c.i] >= options.max_pairs_per_image || count[c.j] >= options.max_pairs_per_image)
      continue;
    ++count[c.i];
    ++count[c.j];
    pairs.emplace_back(c.i, c.j);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace satmesh
