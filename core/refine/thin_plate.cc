#include "core/refine/thin_plate.h"

namespace satmesh {

std::vector<Eigen::Vector3f> Umbrella(const std::vector<Eigen::Vector3f>& positions,
                                      const VertexAdjacency& adjacency) {
  std::vector<Eigen::Vector3f> out(positions.size(), Eigen::Vector3f::Zero());
#pragma omp parallel for schedule(static)
  for (long v = 0; v < long(positions.size()); ++v) {
    const int begin = adjacency.neighbor_offsets[v], end = adjacency.neighbor_offsets[v + 1];
    if (end == begin) continue;
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    for (int k = begin; k < end; ++k) mean += positions[adjacency.neighbors[k]];
    out[v] = mean / float(end - begin) - positions[v];
  }
  return out;
}

std::vector<Eigen::Vector3f> UmbrellaSquared(const std::vector<Eigen::Vector3f>& positions,
                                             const VertexAdjacency& adjacency) {
  return Umbrella(Umbrella(positions, adjacency), adjacency);
}

}  // namespace satmesh
