#include "core/mesh/mesh_clean.h"

#include <gtest/gtest.h>

#include "tests/core/mesh/mesh_fixtures.h"

namespace satmesh {
namespace {

TEST(MeshCleanOptions, DefaultsAreValid) { EXPECT_EQ(MeshCleanOptions{}.Check(), ""); }

TEST(MeshCleanOptions, InvalidDistance) {
  MeshCleanOptions o;
  o.merge_distance_m = 0;
  EXPECT_NE(o.Check().find("merge_distance_m"), std::string::npos);
}

TEST(CleanMesh, CleanGridIsUnchanged) {
  TriangleMesh mesh = testing::CreateGridMesh(6, 1.f, /*wavy=*/true);
  const TriangleMesh before = mesh;
  EXPECT_EQ(CleanMesh(&mesh).Total(), 0u);
  EXPECT_EQ(mesh.vertices, before.vertices);
  EXPECT_EQ(mesh.faces, before.faces);
}

TEST(CleanMesh, RemovesEachKindOfDebris) {
  TriangleMesh mesh = testing::CreateGridMesh(2);  // 9 vertices, 8 faces
  mesh.height_sigma.assign(9, 0.5f);
  // A vertex 0.1 mm from vertex 4 (a cut point next to a vertex) and a face using it in
  // place of 4: after merging it duplicates face 0 (0, 1, 4).
  mesh.vertices.emplace_back(1.0001f, 1.f, 0.f);
  mesh.height_sigma.push_back(9.f);
  mesh.faces.emplace_back(0, 1, 9);
  // Three collinear points (zero area) and a needle 0.2 mm high.
  mesh.vertices.emplace_back(3.f, 0.f, 0.f);
  mesh.vertices.emplace_back(4.f, 0.f, 0.f);
  mesh.vertices.emplace_back(5.f, 0.0002f, 0.f);
  mesh.height_sigma.insert(mesh.height_sigma.end(), {1.f, 1.f, 1.f});
  mesh.faces.emplace_back(2, 10, 11);
  mesh.faces.emplace_back(10, 11, 12);
  // A face with a repeated index and an unreferenced vertex.
  mesh.faces.emplace_back(3, 3, 4);
  mesh.vertices.emplace_back(7.f, 7.f, 7.f);
  mesh.height_sigma.push_back(1.f);

  const MeshDebris found = FindDebris(mesh);
  EXPECT_EQ(found.close_vertices, 1u);
  EXPECT_EQ(found.degenerate_faces, 3u);
  EXPECT_EQ(found.duplicate_faces, 1u);
  EXPECT_EQ(found.unreferenced_vertices, 4u);  // 10, 11, 12 (only degenerate faces) and 13
  const MeshDebris removed = CleanMesh(&mesh);
  EXPECT_EQ(removed.Total(), found.Total());
  EXPECT_EQ(mesh.vertices.size(), 9u);
  EXPECT_EQ(mesh.faces.size(), 8u);
  EXPECT_EQ(mesh.height_sigma, std::vector<float>(9, 0.5f));  // the kept vertices' sigma
  EXPECT_EQ(FindDebris(mesh).Total(), 0u);
}

TEST(CleanMesh, WellShapedSmallTrianglesStay) {
  // 5 mm triangles are far above the 1 mm thresholds.
  TriangleMesh mesh = testing::CreateGridMesh(4, 0.005f);
  EXPECT_EQ(CleanMesh(&mesh).Total(), 0u);
  EXPECT_EQ(mesh.faces.size(), 32u);
}

}  // namespace
}  // namespace satmesh
