#include "core/refine/significance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/common/error.h"

#include "tests/core/mesh/mesh_fixtures.h"

namespace satmesh {
namespace {

// A 40 x 40 m grid of 1 m at z = 0 (the initial surface), refined: every vertex off by
// Gaussian noise of its sigma (0.1 m), and the vertices of the square [10, 20]^2 also by a
// real change of 1 m (10 sigmas); the vertex (5, 5) no image saw.
constexpr int kUnseen = 5 * 41 + 5;

struct Refined {
  TriangleMesh initial, refined;
  std::vector<float> noise;
};

Refined NoisyPlaneWithAChange() {
  Refined r;
  r.initial = testing::CreateGridMesh(40, 1.f);
  r.refined = r.initial;
  std::mt19937 gen(7);
  std::normal_distribution<float> n(0.f, 0.1f);
  r.refined.height_sigma.assign(r.refined.num_vertices(), 0.1f);
  for (size_t v = 0; v < r.refined.num_vertices(); ++v) {
    Eigen::Vector3f& p = r.refined.vertices[v];
    r.noise.push_back(n(gen));
    p.z() += r.noise.back();
    if (p.x() >= 10 && p.x() <= 20 && p.y() >= 10 && p.y() <= 20) p.z() += 1.f;
  }
  r.refined.height_sigma[kUnseen] = std::numeric_limits<float>::infinity();
  return r;
}

bool InChange(const Eigen::Vector3f& p) {
  return p.x() >= 11 && p.x() <= 19 && p.y() >= 11 && p.y() <= 19;  // away from its edge
}

TEST(KeepSignificantChanges, NoiseReturnsToTheInitialSurfaceARealChangeStays) {
  Refined r = NoisyPlaneWithAChange();
  TriangleMesh mesh = r.refined;
  const SignificanceStats stats =
      KeepSignificantChanges(r.initial, /*k=*/2, /*max_offset_m=*/3, /*hold_boundary_xy=*/true, &mesh);
  // Vertical rays along the grid's own border edges may miss it: nearly all others hit.
  EXPECT_GT(stats.vertices, mesh.num_vertices() - 4 * 40);
  double noise_before = 0, noise_after = 0;
  int flat = 0;
  for (size_t v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    if (InChange(p)) {
      // 10 sigmas: kept (weight 10^4 / (10^4 + 2^4) > 0.998), noise included.
      EXPECT_NEAR(p.z(), r.refined.vertices[v].z(), 0.01f) << v;
    } else if (p.x() < 8 || p.x() > 22 || p.y() < 8 || p.y() > 22) {
      noise_before += double(r.noise[v]) * r.noise[v];
      noise_after += double(p.z()) * p.z();
      ++flat;
      // Stays on the normal through the vertex: x, y barely move on a plane.
      EXPECT_NEAR(p.x(), r.refined.vertices[v].x(), 0.05f) << v;
    }
  }
  ASSERT_GT(flat, 1000);
  // Offsets within noise mostly undone: of 1 sigma RMS, under half a sigma is left (the
  // 5% of offsets beyond 2 sigmas stay, as a real change would).
  EXPECT_LT(std::sqrt(noise_after / flat), 0.5 * std::sqrt(noise_before / flat));
  // The vertex no image saw is back on the initial surface.
  EXPECT_NEAR(mesh.vertices[kUnseen].z(), 0.f, 1e-5f);
  EXPECT_GT(stats.mean_gain, 0.02);
  EXPECT_LT(stats.mean_gain, 0.3);
}

TEST(KeepSignificantChanges, OffsetsBeyondReachAndBadArgumentsAreLeftAlone) {
  Refined r = NoisyPlaneWithAChange();
  TriangleMesh mesh = r.refined;
  for (auto& p : mesh.vertices) p.z() += 5.f;  // 5 m off: beyond a reach of 3 m
  const TriangleMesh before = mesh;
  const SignificanceStats stats = KeepSignificantChanges(r.initial, 2, 3, true, &mesh);
  EXPECT_EQ(stats.vertices, 0u);
  for (size_t v = 0; v < mesh.num_vertices(); ++v) EXPECT_EQ(mesh.vertices[v], before.vertices[v]);
  EXPECT_THROW(KeepSignificantChanges(r.initial, 0, 3, true, &mesh), Error);
  mesh.height_sigma.clear();
  EXPECT_THROW(KeepSignificantChanges(r.initial, 2, 3, true, &mesh), Error);
}

}  // namespace
}  // namespace satmesh
