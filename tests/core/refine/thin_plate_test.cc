#include "core/refine/thin_plate.h"

#include <gtest/gtest.h>

#include "core/mesh/mesh.h"

namespace satmesh {
namespace {

// A fan: vertex 0 at the origin, five neighbours on the unit circle in the plane z = 0 and
// one 10 m below (a roof edge joined to a wall's foot by a one-cell wall strip).
TriangleMesh Fan(float drop_m) {
  TriangleMesh mesh;
  mesh.vertices.push_back({0, 0, 0});
  for (int k = 0; k < 5; ++k) {
    const float a = float(k) * 2.f * float(M_PI) / 6.f;
    mesh.vertices.push_back({std::cos(a), std::sin(a), 0});
  }
  mesh.vertices.push_back({std::cos(5 * 2.f * float(M_PI) / 6.f),
                           std::sin(5 * 2.f * float(M_PI) / 6.f), -drop_m});
  for (int k = 0; k < 6; ++k) mesh.faces.push_back({0, 1 + k, 1 + (k + 1) % 6});
  return mesh;
}

TEST(Umbrella, InverseLengthWeightsLetAFarNeighbourPullLess) {
  const TriangleMesh mesh = Fan(10.f);
  const VertexAdjacency adjacency = BuildVertexAdjacency(mesh);
  const std::vector<float> weights = InverseLengthWeights(mesh.vertices, adjacency);
  ASSERT_EQ(weights.size(), adjacency.neighbors.size());
  const float far = 1.f / std::sqrt(1.f + 100.f);
  // Uniform: the mean of six neighbours, one 10 m down: -10 / 6 m.
  EXPECT_NEAR(Umbrella(mesh.vertices, adjacency)[0].z(), -10.f / 6.f, 1e-5f);
  // Weighted: five at weight 1, one at 1 / sqrt(101).
  EXPECT_NEAR(Umbrella(mesh.vertices, adjacency, &weights)[0].z(), -10.f * far / (5.f + far), 1e-5f);
  // Empty weights are uniform.
  const std::vector<float> none;
  EXPECT_EQ(Umbrella(mesh.vertices, adjacency, &none)[0], Umbrella(mesh.vertices, adjacency)[0]);
}

TEST(Umbrella, WeightedIsZeroOnAPlaneAndLinearInThePositions) {
  // A planar fan: every vertex's weighted umbrella of the centre is zero (symmetric ring).
  const TriangleMesh flat = Fan(0.f);
  const VertexAdjacency adjacency = BuildVertexAdjacency(flat);
  const std::vector<float> weights = InverseLengthWeights(flat.vertices, adjacency);
  EXPECT_LT(Umbrella(flat.vertices, adjacency, &weights)[0].norm(), 1e-6f);
  // Fixed weights: U²(a + b) = U²(a) + U²(b), what the offsets' smoothing relies on.
  std::vector<Eigen::Vector3f> a = flat.vertices, b(flat.vertices.size()), sum(flat.vertices.size());
  for (size_t v = 0; v < b.size(); ++v) {
    b[v] = Eigen::Vector3f(0.1f * float(v), -0.2f, 0.3f * float(v % 3));
    sum[v] = a[v] + b[v];
  }
  const auto ua = UmbrellaSquared(a, adjacency, &weights), ub = UmbrellaSquared(b, adjacency, &weights),
             us = UmbrellaSquared(sum, adjacency, &weights);
  for (size_t v = 0; v < us.size(); ++v) EXPECT_LT((us[v] - ua[v] - ub[v]).norm(), 1e-5f) << v;
}

}  // namespace
}  // namespace satmesh
