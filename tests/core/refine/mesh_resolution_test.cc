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

}  // namespace
}  // namespace satmesh
