#include "core/refine/thin_plate.h"

#include <algorithm>

namespace satmesh {

std::vector<float> InverseLengthWeights(const std::vector<Eigen::Vector3f>& positions,
                                        const VertexAdjacency& adjacency) {
  std::vector<float> weights(adjacency.neighbors.size());
#pragma omp parallel for schedule(static)
  for (long v = 0; v < long(positions.size()); ++v)
    for (int k = adjacency.neighbor_offsets[v]; k < adjacency.neighbor_offsets[v + 1]; ++k)
      weights[k] = 1.f / std::max(1e-3f, (positions[adjacency.neighbors[k]] - positions[v]).norm());
  return weights;
}

std::vector<Eigen::Vector3f> Umbrella(const std::vector<Eigen::Vector3f>& positions,
                                      const VertexAdjacency& adjacency,
                                      const std::vector<float>* weights) {
  const float* w = weights && !weights->empty() ? weights->data() : nullptr;
  std::vector<Eigen::Vector3f> out(positions.size(), Eigen::Vector3f::Zero());
#pragma omp parallel for schedule(static)
  for (long v = 0; v < long(positions.size()); ++v) {
    const int begin = adjacency.neighbor_offsets[v], end = adjacency.neighbor_offsets[v + 1];
    if (end == begin) continue;
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    float sum = 0;  // uniform: exactly the neighbour count, so the mean is the plain one
    for (int k = begin; k < end; ++k) {
      const float wk = w ? w[k] : 1.f;
      mean += wk * positions[adjacency.neighbors[k]];
      sum += wk;
    }
    out[v] = mean / sum - positions[v];
  }
  return out;
}

std::vector<Eigen::Vector3f> UmbrellaSquared(const std::vector<Eigen::Vector3f>& positions,
                                             const VertexAdjacency& adjacency,
                                             const std::vector<float>* weights) {
  return Umbrella(Umbrella(positions, adjacency, weights), adjacency, weights);
}

}  // namespace satmesh
