#include "core/raycast/ray_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "core/common/error.h"

namespace satmesh {
namespace {

constexpr float kTol = 1e-5f;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// Unit square [0,1]^2 at height z, faces (0,1,2) and (0,2,3), normals +z.
TriangleMesh CreateSquare(float z = 0.f) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, z}, {1, 0, z}, {1, 1, z}, {0, 1, z}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

// Axis-aligned box [lo, hi], 12 outward-facing triangles (2 per side).
TriangleMesh CreateBox(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.push_back({(i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                             (i & 4) ? hi.z() : lo.z()});
  }
  mesh.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},   // z-, z+
                {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},   // y-, y+
                {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};  // x-, x+
  return mesh;
}

Ray Down(float x, float y, float z0 = 2.f) {
  return Ray{{x, y, z0}, {0, 0, -1}};
}

TEST(RaySceneIntersect, HitsPlaneExactly) {
  RayScene scene(CreateSquare());
  RayHit hit = scene.Intersect(Down(0.75f, 0.25f));
  ASSERT_TRUE(hit.hit());
  EXPECT_EQ(hit.face, 0);
  EXPECT_NEAR(hit.t, 2.f, kTol);
  // p = (1-u-v) p0 + u p1 + v p2 = (u + v, v)
  EXPECT_NEAR(hit.u, 0.5f, kTol);
  EXPECT_NEAR(hit.v, 0.25f, kTol);

  hit = scene.Intersect(Down(0.2f, 0.7f));
  ASSERT_TRUE(hit.hit());
  EXPECT_EQ(hit.face, 1);  // face (0,2,3): p = (u, u + v)
  EXPECT_NEAR(hit.u, 0.2f, kTol);
  EXPECT_NEAR(hit.v, 0.5f, kTol);
}

TEST(RaySceneIntersect, TIsInUnitsOfDirection) {
  RayScene scene(CreateSquare());
  RayHit hit = scene.Intersect(Ray{{0.5f, 0.1f, 3.f}, {0, 0, -2}});
  ASSERT_TRUE(hit.hit());
  EXPECT_NEAR(hit.t, 1.5f, kTol);
}

TEST(RaySceneIntersect, HitsBackFacesToo) {
  RayScene scene(CreateSquare());
  RayHit hit = scene.Intersect(Ray{{0.5f, 0.1f, -1.f}, {0, 0, 1}});
  ASSERT_TRUE(hit.hit());
  EXPECT_NEAR(hit.t, 1.f, kTol);
}

TEST(RaySceneIntersect, Misses) {
  RayScene scene(CreateSquare());
  EXPECT_FALSE(scene.Intersect(Down(1.5f, 0.5f)).hit());              // beside
  EXPECT_FALSE(scene.Intersect(Ray{{0.5f, 0.5f, 2.f}, {0, 0, 1}}).hit());  // away
  EXPECT_FALSE(scene.Intersect(Ray{{0.5f, 0.5f, 2.f}, {0, 0, -1}, 0.f, 1.9f}).hit());
  EXPECT_FALSE(scene.Intersect(Ray{{0.5f, 0.5f, 2.f}, {0, 0, -1}, 2.1f, 5.f}).hit());
}

TEST(RaySceneIntersect, NonFiniteRaysAreMisses) {
  RayScene scene(CreateSquare());
  std::vector<Ray> rays = {
      Ray{{kNaN, 0.5f, 2.f}, {0, 0, -1}},
      Ray{{0.5f, 0.5f, 2.f}, {0, kNaN, -1}},
      Ray{{0.5f, 0.5f, 2.f}, {0, 0, -1}, kNaN, 10.f},
      Ray{{0.5f, 0.5f, 2.f}, {0, 0, -1}, 0.f, kNaN},
      Ray{{0.5f, 0.5f, std::numeric_limits<float>::infinity()}, {0, 0, -1}},
      Ray{{0.5f, 0.5f, 2.f}, {0, 0, 0}},
      Down(0.5f, 0.25f),  // a good ray in the same packet still hits
  };
  std::vector<RayHit> hits(rays.size());
  scene.Intersect(rays.data(), hits.data(), rays.size());
  for (size_t i = 0; i + 1 < rays.size(); ++i) EXPECT_FALSE(hits[i].hit()) << "ray " << i;
  EXPECT_TRUE(hits.back().hit());
  std::vector<unsigned char> occluded(rays.size(), 7);
  scene.Occluded(rays.data(), occluded.data(), rays.size());
  for (size_t i = 0; i + 1 < rays.size(); ++i) EXPECT_EQ(occluded[i], 0) << "ray " << i;
  EXPECT_EQ(occluded.back(), 1);
}

TEST(RaySceneIntersect, BoxFacesAndDistances) {
  RayScene scene(CreateBox({0, 0, 0}, {2, 3, 4}));
  // From -x towards +x at (y, z) = (1, 1): hits the x=0 side (faces 8/9) at t = 5.
  RayHit hit = scene.Intersect(Ray{{-5, 1, 1}, {1, 0, 0}});
  ASSERT_TRUE(hit.hit());
  EXPECT_NEAR(hit.t, 5.f, kTol);
  EXPECT_TRUE(hit.face == 8 || hit.face == 9) << hit.face;
  // From above: top side (faces 2/3) at z = 4.
  hit = scene.Intersect(Ray{{0.5f, 0.5f, 10}, {0, 0, -1}});
  ASSERT_TRUE(hit.hit());
  EXPECT_NEAR(hit.t, 6.f, kTol);
  EXPECT_TRUE(hit.face == 2 || hit.face == 3) << hit.face;
  // From inside: the nearest side.
  hit = scene.Intersect(Ray{{1, 0.5f, 2}, {0, -1, 0}});
  ASSERT_TRUE(hit.hit());
  EXPECT_NEAR(hit.t, 0.5f, kTol);
  EXPECT_TRUE(hit.face == 4 || hit.face == 5) << hit.face;
}

TEST(RaySceneIntersect, ManyRaysMatchAnalyticPlane) {
  // A tilted plane z = 0.3 x - 0.2 y + 1 over [0,1]^2, many oblique rays (several packets).
  TriangleMesh mesh = CreateSquare();
  for (auto& p : mesh.vertices) p.z() = 0.3f * p.x() - 0.2f * p.y() + 1.f;
  RayScene scene(mesh);
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> uni(0.05f, 0.95f);
  std::vector<Ray> rays;
  std::vector<Eigen::Vector3f> targets;
  for (int i = 0; i < 1000; ++i) {
    Eigen::Vector3f target(uni(rng), uni(rng), 0.f);
    target.z() = 0.3f * target.x() - 0.2f * target.y() + 1.f;
    Eigen::Vector3f dir(uni(rng) - 0.5f, uni(rng) - 0.5f, -1.f);
    rays.push_back(Ray{target - 3.f * dir, dir});
    targets.push_back(target);
  }
  std::vector<RayHit> hits(rays.size());
  scene.Intersect(rays.data(), hits.data(), rays.size());
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(hits[i].hit()) << i;
    EXPECT_NEAR(hits[i].t, 3.f, 1e-5f) << i;
    const Eigen::Vector3i& f = mesh.faces[hits[i].face];
    Eigen::Vector3f p = (1 - hits[i].u - hits[i].v) * mesh.vertices[f[0]] +
                        hits[i].u * mesh.vertices[f[1]] + hits[i].v * mesh.vertices[f[2]];
    EXPECT_LT((p - targets[i]).norm(), 1e-5f) << i;
  }
}

TEST(RaySceneUpdateVertices, MovesHits) {
  TriangleMesh mesh = CreateSquare();
  RayScene scene(mesh);
  EXPECT_NEAR(scene.Intersect(Down(0.5f, 0.25f)).t, 2.f, kTol);
  for (auto& p : mesh.vertices) p.z() += 1.f;
  scene.UpdateVertices(mesh.vertices);
  EXPECT_NEAR(scene.Intersect(Down(0.5f, 0.25f)).t, 1.f, kTol);
  // Move it sideways out of the ray's way.
  for (auto& p : mesh.vertices) p.x() += 5.f;
  scene.UpdateVertices(mesh.vertices);
  EXPECT_FALSE(scene.Intersect(Down(0.5f, 0.25f)).hit());
  EXPECT_TRUE(scene.Intersect(Down(5.5f, 0.25f)).hit());
}

TEST(RaySceneUpdateVertices, RejectsWrongCountAndNaN) {
  TriangleMesh mesh = CreateSquare();
  RayScene scene(mesh);
  mesh.vertices.pop_back();
  EXPECT_THROW(scene.UpdateVertices(mesh.vertices), Error);
  mesh = CreateSquare();
  mesh.vertices[2].y() = kNaN;
  EXPECT_THROW(scene.UpdateVertices(mesh.vertices), Error);
}

TEST(RaySceneConstruct, RejectsBadIndexAndNaN) {
  TriangleMesh mesh = CreateSquare();
  mesh.faces.push_back({0, 1, 4});
  EXPECT_THROW(RayScene{mesh}, Error);
  mesh = CreateSquare();
  mesh.vertices[0].x() = kNaN;
  EXPECT_THROW(RayScene{mesh}, Error);
}

TEST(RaySceneConstruct, EmptyMeshMissesEverything) {
  RayScene scene(TriangleMesh{});
  EXPECT_FALSE(scene.Intersect(Down(0.5f, 0.5f)).hit());
  unsigned char occluded = 7;
  Ray ray = Down(0.5f, 0.5f);
  scene.Occluded(&ray, &occluded, 1);
  EXPECT_EQ(occluded, 0);
}

TEST(RaySceneOccluded, RespectsRange) {
  RayScene scene(CreateBox({0, 0, 0}, {1, 1, 1}));
  std::vector<Ray> rays = {
      Ray{{-1, 0.5f, 0.5f}, {1, 0, 0}, 0.f, 0.9f},   // stops short of the box
      Ray{{-1, 0.5f, 0.5f}, {1, 0, 0}, 0.f, 1.1f},   // reaches it
      Ray{{-1, 0.5f, 0.5f}, {-1, 0, 0}},             // points away
      Ray{{0.5f, 0.5f, 5}, {0, 0, -1}},              // from above
  };
  std::vector<unsigned char> occluded(rays.size());
  scene.Occluded(rays.data(), occluded.data(), rays.size());
  EXPECT_EQ(occluded[0], 0);
  EXPECT_EQ(occluded[1], 1);
  EXPECT_EQ(occluded[2], 0);
  EXPECT_EQ(occluded[3], 1);
}

}  // namespace
}  // namespace satmesh
