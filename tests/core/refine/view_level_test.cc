#include "core/refine/view_level.h"

#include <gtest/gtest.h>

#include <random>

#include "core/image/image.h"
#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

// A plane with a 3 m block in the middle (steep walls: occlusion edges in oblique views).
TriangleMesh BlockMesh() {
  TriangleMesh mesh = testing::PlaneMesh(testing::Plane{}, 20, 1.0, 0.0);
  for (auto& p : mesh.vertices)
    if (std::abs(p.x()) < 5.5f && std::abs(p.y()) < 5.5f) p.z() += 3.f;
  return mesh;
}

ViewLevel MakeView(const RefineInput& input, int v) {
  return MakeViewLevel(v, 0, NormalizeRadiometry(input.views[v].image), input.views[v].rpc,
                       input.frame, Eigen::Vector3d(-30, -30, -15), Eigen::Vector3d(30, 30, 20), 8);
}

TEST(UpdateHitMap, FollowsSmallVertexMovesLikeAFullRaycast) {
  TriangleMesh mesh = BlockMesh();
  const RefineInput input = testing::MakePlaneInput(testing::Plane{}, {{25, 40}}, mesh, 120, 0.5);
  ViewLevel updated = MakeView(input, 0);
  RayScene scene(mesh);
  CastHitMap(scene, &updated);

  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.05f, 0.05f);  // 0.1 GSD moves
  for (auto& p : mesh.vertices) p += Eigen::Vector3f(u(rng), u(rng), u(rng));
  scene.UpdateVertices(mesh.vertices);
  const HitMapUpdate stats = UpdateHitMap(scene, mesh, 0.02f, 1.5f, &updated);
  ViewLevel fresh = MakeView(input, 0);
  CastHitMap(scene, &fresh);

  long both = 0, close = 0, hit_mismatch = 0;
  for (size_t p = 0; p < fresh.hit_map.hits.size(); ++p) {
    const bool a = updated.hit_map.hits[p].hit(), b = fresh.hit_map.hits[p].hit();
    if (a != b) ++hit_mismatch;
    if (!a || !b) continue;
    ++both;
    if ((updated.hit_map.points[p] - fresh.hit_map.points[p]).norm() < 0.01f) ++close;
  }
  std::printf("kept %ld recast %ld; within 1 cm %.4f; hit mismatch %ld of %ld\n", stats.kept,
              stats.recast, double(close) / both, hit_mismatch, both);
  ASSERT_GT(both, 5000);
  EXPECT_GT(stats.kept, 0.8 * both);               // most pixels need no ray tracing
  EXPECT_GT(stats.recast, 0);                       // the block's edges were traced again
  EXPECT_GT(double(close) / both, 0.995);           // and the result is the raycast's
  EXPECT_LT(double(hit_mismatch) / both, 0.002);
}

}  // namespace
}  // namespace satmesh
