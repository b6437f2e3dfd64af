#pragma once
// Stereo pair selection (paper 4.2): pairs whose viewing directions intersect at
// min..max degrees, images with poor contrast dropped, at most N pairs per image
// (preferring angles near the middle of the range).
#include <Eigen/Core>
#include <utility>
#include <vector>

#include "core/refine/refine_options.h"

namespace satmesh {

struct PairCandidateView {
  Eigen::Vector3d direction;  // unit viewing direction (towards the ground)
  double contrast = 0;        // std of the normalised image
};

std::vector<std::pair<int, int>> SelectPairs(const std::vector<PairCandidateView>& views,
                                             const PairOptions& options);

double IntersectionAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace satmesh
