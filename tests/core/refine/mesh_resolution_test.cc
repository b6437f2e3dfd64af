#include "core/refine/mesh_resolution.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "tests/core/mesh/mesh_fixtures.h"

namespace satmesh {
namespace {

// A 40x40 grid of 1 m with a 3 m high block over [16, 24]^2 (a roof on a street).
TriangleMesh BlockOnPlane() {
  TriangleMesh mesh = testing::CreateGridMesh(40, 1.f);
  for (auto& v : mesh.vertices)
    if (v.x() >= 16 && v.x() <= 24 && v.y() >= 16 && v.y() <= 24) v.z() = 3.f;
  return mesh;
}

TEST(VertexBendingM, ZeroOnAPlaneWhateverTheTrianglesIsTheStepAtAnEdge) {
  // A tilted plane subdivided unevenly: every interior vertex has zero bending.
  TriangleMesh plane = testing::CreateGridMesh(6, 1.f);
  for (auto& v : plane.vertices) v.z() = 0.3f * v.x() - 0.2f * v.y();
  std::vector<char> marked(plane.num_faces(), 0);
  marked[13] = marked[30] = 1;
  plane = SubdivideMarked(plane, marked);
  const VertexAdjacency adj = BuildVertexAdjacency(plane);
  const std::vector<float> bending = VertexBendingM(plane, adj);
  for (size_t v = 0; v < plane.num_vertices(); ++v) {
    if (!adj.is_boundary[v]) EXPECT_NEAR(bending[v], 0.f, 1e-5f) << v;
  }
  // The block's top corner (24, 24, 3): neighbours are lower on two sides, so it bends
  // by a sizeable fraction of the 3 m step; a vertex in the roof's middle does not.
  const TriangleMesh block = BlockOnPlane();
  const std::vector<float> b = VertexBendingM(block, BuildVertexAdjacency(block));
  EXPECT_GT(b[24 * 41 + 24], 0.5f);
  EXPECT_NEAR(b[20 * 41 + 20], 0.f, 1e-6f);
  EXPECT_NEAR(b[6 * 41 + 6], 0.f, 1e-6f);
}

TEST(FacesToSubdivide, TheBlocksEdgesAndTheBorderNotTheFlats) {
  const TriangleMesh block = BlockOnPlane();
  const std::vector<char> marked = FacesToSubdivide(block, 0.1);
  auto face_at = [&](float x, float y) {  // the face whose centroid is nearest (x, y)
    size_t best = 0;
    float best_d = 1e30f;
    for (size_t f = 0; f < block.num_faces(); ++f) {
      Eigen::Vector3f c = Eigen::Vector3f::Zero();
      for (int k = 0; k < 3; ++k) c += block.vertices[block.faces[f][k]] / 3.f;
      const float d = std::hypot(c.x() - x, c.y() - y);
      if (d < best_d) best_d = d, best = f;
    }
    return best;
  };
  EXPECT_TRUE(marked[face_at(15.7f, 20.f)]);  // the block's west wall
  EXPECT_TRUE(marked[face_at(24.7f, 24.3f)]);  // its north-east corner
  EXPECT_TRUE(marked[face_at(0.3f, 20.f)]);    // the open border
  EXPECT_FALSE(marked[face_at(20.f, 20.f)]);   // the middle of the roof
  EXPECT_FALSE(marked[face_at(8.f, 8.f)]);     // the street
  EXPECT_FALSE(marked[face_at(32.f, 20.f)]);
  size_t count = 0;
  for (char m : marked) count += m;
  EXPECT_LT(count, block.num_faces() / 2);
  // Tolerance 0: every face, as Subdivide1To4.
  const std::vector<char> all = FacesToSubdivide(block, 0.0);
  EXPECT_EQ(size_t(std::count(all.begin(), all.end(), 1)), block.num_faces());
}

// A fine (0.5 m) plane with a narrow 1 m high ridge along x = 9, which a coarse 2 m grid
// misses (its vertices sit at even x).
TriangleMesh FineSurfaceWithRidge() {
  TriangleMesh fine = testing::CreateGridMesh(80, 0.5f);
  for (auto& v : fine.vertices)
    if (std::abs(v.x() - 9.f) < 0.3f) v.z() = 1.f;
  return fine;
}

TEST(DistanceAlong, SignedDistanceToTheNearerSideWithinReach) {
  const TriangleMesh fine = FineSurfaceWithRidge();
  const RayScene scene(fine);
  const std::vector<Eigen::Vector3f> points = {{4.1f, 4.2f, 0.3f}, {4.1f, 4.2f, -0.5f},
                                               {9.f, 20.1f, 0.2f}, {4.1f, 4.2f, 5.f}};
  const std::vector<Eigen::Vector3f> up(points.size(), Eigen::Vector3f::UnitZ());
  const std::vector<float> d = DistanceAlong(scene, points, up, 2.0);
  EXPECT_NEAR(d[0], -0.3f, 1e-5f);  // the plane below
  EXPECT_NEAR(d[1], 0.5f, 1e-5f);   // the plane above
  EXPECT_NEAR(d[2], 0.8f, 1e-5f);   // the ridge's top above
  EXPECT_TRUE(std::isnan(d[3]));    // 5 m off: beyond reach
}

TEST(FollowInitialDetail, SubdividesWhereTheCoarseMeshMissesTheSurfaceAndPutsTheNewVerticesOnIt) {
  const TriangleMesh fine = FineSurfaceWithRidge();
  const RayScene scene(fine);
  TriangleMesh coarse = testing::CreateGridMesh(20, 2.f);  // flat, vertices at even x: misses the ridge
  size_t subdivided = 0;
  const TriangleMesh out = FollowInitialDetail(coarse, scene, 0.25, 2.0, &subdivided);
  // Only the faces over the ridge (the column of cells 8 <= x <= 10) depart by > 0.25 m.
  EXPECT_EQ(subdivided, size_t(2 * 20));
  // Each marked face becomes 4; its unmarked neighbours across a split edge are bisected.
  EXPECT_GE(out.num_faces(), coarse.num_faces() + 3 * subdivided);
  EXPECT_LE(out.num_faces(), coarse.num_faces() + 3 * subdivided + 2 * 21);
  // Original vertices keep their place; the new ones on x = 9 sit on the ridge (z = 1),
  // the others on the plane.
  for (size_t v = 0; v < coarse.num_vertices(); ++v) EXPECT_EQ(out.vertices[v], coarse.vertices[v]);
  int on_ridge = 0;
  for (size_t v = coarse.num_vertices(); v < out.num_vertices(); ++v) {
    const Eigen::Vector3f& p = out.vertices[v];
    const float expected = std::abs(p.x() - 9.f) < 0.3f ? 1.f : 0.f;
    EXPECT_NEAR(p.z(), expected, 1e-5f) << p.transpose();
    on_ridge += expected == 1.f;
  }
  // On x = 9: the midpoints of the 21 edges from x = 8 to x = 10 and of the 20 diagonals.
  EXPECT_EQ(on_ridge, 41);
  // A surface the coarse mesh already holds: nothing to do.
  const RayScene flat_scene(testing::CreateGridMesh(80, 0.5f));
  const TriangleMesh same = FollowInitialDetail(coarse, flat_scene, 0.25, 2.0, &subdivided);
  EXPECT_EQ(subdivided, 0u);
  EXPECT_EQ(same.num_faces(), coarse.num_faces());
}

}  // namespace
}  // namespace satmesh
