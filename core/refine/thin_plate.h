#pragma once
// Thin-plate smoothness through the umbrella operator (Kobbelt):
//   U(v) = mean_{w∈N(v)} p_w - p_v,   U²(v) = mean_{w∈N(v)} U(w) - U(v)
// The smoothing displacement of the thin-plate energy is -U²(v). With weights, the mean is
// weighted: U(v) = Σ_w λ_vw p_w / Σ_w λ_vw - p_v; the scale-dependent umbrella (Desbrun et
// al. 1999) takes λ_vw = 1 / |p_w - p_v| (InverseLengthWeights), so a neighbour far away (a
// wall's foot seen from a roof edge through a grid mesh's one-cell wall strip) pulls less.
#include <Eigen/Core>
#include <vector>

#include "core/mesh/topology.h"

namespace satmesh {

// One weight per entry of adjacency.neighbors: 1 / the edge's length in `positions`
// (edges shorter than 1 mm count as 1 mm).
std::vector<float> InverseLengthWeights(const std::vector<Eigen::Vector3f>& positions,
                                        const VertexAdjacency& adjacency);

// weights: per entry of adjacency.neighbors; null or empty: uniform. Fixed weights keep the
// operator linear in the positions.
std::vector<Eigen::Vector3f> Umbrella(const std::vector<Eigen::Vector3f>& positions,
                                      const VertexAdjacency& adjacency,
                                      const std::vector<float>* weights = nullptr);
// U²(v) for every vertex (0 for isolated vertices), both applications with `weights`.
std::vector<Eigen::Vector3f> UmbrellaSquared(const std::vector<Eigen::Vector3f>& positions,
                                             const VertexAdjacency& adjacency,
                                             const std::vector<float>* weights = nullptr);

}  // namespace satmesh
