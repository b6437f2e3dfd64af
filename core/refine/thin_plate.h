#pragma once
// Thin-plate smoothness through the umbrella operator (Kobbelt):
//   U(v) = mean_{w∈N(v)} p_w - p_v,   U²(v) = mean_{w∈N(v)} U(w) - U(v)
// The smoothing displacement of the thin-plate energy is -U²(v).
#include <Eigen/Core>
#include <vector>

#include "core/mesh/topology.h"

namespace satmesh {

std::vector<Eigen::Vector3f> Umbrella(const std::vector<Eigen::Vector3f>& positions,
                                      const VertexAdjacency& adjacency);
// U²(v) for every vertex (0 for isolated vertices).
std::vector<Eigen::Vector3f> UmbrellaSquared(const std::vector<Eigen::Vector3f>& positions,
                                             const VertexAdjacency& adjacency);

}  // namespace satmesh
