#include "core/mesh/topology.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "tests/core/mesh/mesh_fixtures.h"

namespace satmesh {
namespace {

std::vector<int> Neighbors(const VertexAdjacency& adj, int v) {
  return {adj.neighbors.begin() + adj.neighbor_offsets[v],
          adj.neighbors.begin() + adj.neighbor_offsets[v + 1]};
}

TEST(BuildVertexAdjacency, GridOneRingsAndBoundary) {
  const TriangleMesh mesh = testing::CreateGridMesh(3);  // 4x4 vertices
  const VertexAdjacency adj = BuildVertexAdjacency(mesh);
  ASSERT_EQ(adj.neighbor_offsets.size(), 17u);
  // Interior vertex 5 = (1,1): 6 neighbours, 6 faces.
  EXPECT_EQ(Neighbors(adj, 5), (std::vector<int>{0, 1, 4, 6, 9, 10}));  // diagonals run down-right
  EXPECT_EQ(adj.face_offsets[6] - adj.face_offsets[5], 6);
  // Corner 0: neighbours 1, 4, 5; corner 3 has one face.
  EXPECT_EQ(Neighbors(adj, 0), (std::vector<int>{1, 4, 5}));
  EXPECT_EQ(adj.face_offsets[4] - adj.face_offsets[3], 1);
  for (int v = 0; v < 16; ++v) {
    const int r = v / 4, c = v % 4;
    const bool on_border = r == 0 || c == 0 || r == 3 || c == 3;
    EXPECT_EQ(adj.is_boundary[v], on_border) << v;
  }
}

TEST(BuildVertexAdjacency, ClosedCubeHasNoBoundaryAndSymmetricRings) {
  const TriangleMesh mesh = testing::CreateCube();
  const VertexAdjacency adj = BuildVertexAdjacency(mesh);
  size_t total = 0;
  for (int v = 0; v < 8; ++v) {
    EXPECT_FALSE(adj.is_boundary[v]);
    for (int w : Neighbors(adj, v)) {
      const auto ring = Neighbors(adj, w);
      EXPECT_TRUE(std::binary_search(ring.begin(), ring.end(), v));
    }
    total += Neighbors(adj, v).size();
  }
  EXPECT_EQ(total, 2u * 18u);  // 18 edges, each seen from both ends
  EXPECT_EQ(adj.faces.size(), 36u);
}

TEST(BuildVertexAdjacency, IsolatedVertexHasEmptyRing) {
  TriangleMesh mesh = testing::CreateCube();
  mesh.vertices.emplace_back(5, 5, 5);
  const VertexAdjacency adj = BuildVertexAdjacency(mesh);
  EXPECT_TRUE(Neighbors(adj, 8).empty());
  EXPECT_FALSE(adj.is_boundary[8]);
}

TEST(FaceNormals, CubeNormalsPointOutward) {
  const TriangleMesh mesh = testing::CreateCube();
  const auto normals = FaceNormals(mesh);
  const auto areas = FaceAreas(mesh);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3f centroid = (mesh.vertices[mesh.faces[f][0]] +
                                      mesh.vertices[mesh.faces[f][1]] +
                                      mesh.vertices[mesh.faces[f][2]]) / 3.f;
    EXPECT_GT(normals[f].dot(centroid - Eigen::Vector3f::Constant(0.5f)), 0.3f) << f;
    EXPECT_NEAR(normals[f].norm(), 1.f, 1e-6f);
    EXPECT_NEAR(areas[f], 0.5f, 1e-6f);
  }
}

TEST(FaceNormals, DegenerateFaceHasZeroNormal) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  mesh.faces = {{0, 1, 2}};
  EXPECT_EQ(FaceNormals(mesh)[0], Eigen::Vector3f::Zero());
  EXPECT_EQ(FaceAreas(mesh)[0], 0.f);
}

TEST(VertexNormals, CubeCornerNormalIsDiagonal) {
  const auto normals = VertexNormals(testing::CreateCube());
  // Vertex 7 = (1,1,1): area-weighted over 3 faces with unequal triangle counts, but each
  // face contributes its full area split over 1 or 2 triangles; the sum is symmetric.
  EXPECT_NEAR(normals[7].norm(), 1.f, 1e-6f);
  EXPECT_GT(normals[7].x(), 0.f);
  EXPECT_GT(normals[7].y(), 0.f);
  EXPECT_GT(normals[7].z(), 0.f);
  const auto flat = VertexNormals(testing::CreateGridMesh(2));
  for (const auto& n : flat) EXPECT_NEAR(n.z(), 1.f, 1e-6f);
}

TEST(Subdivide1To4, CountsAndSharedMidpoints) {
  const TriangleMesh mesh = testing::CreateGridMesh(4, 2.f, /*wavy=*/true);
  const TriangleMesh fine = Subdivide1To4(mesh);
  // V' = V + E; grid: V = 25, E = 3*16 + 2*4 = 56.
  EXPECT_EQ(UniqueEdges(mesh).size(), 56u);
  EXPECT_EQ(fine.num_vertices(), 25u + 56u);
  EXPECT_EQ(fine.num_faces(), 4 * mesh.num_faces());
  // Originals kept, total area kept (planar split of each triangle), orientation kept.
  for (size_t v = 0; v < mesh.num_vertices(); ++v) EXPECT_EQ(fine.vertices[v], mesh.vertices[v]);
  double area = 0, fine_area = 0;
  for (float a : FaceAreas(mesh)) area += a;
  for (float a : FaceAreas(fine)) fine_area += a;
  EXPECT_NEAR(fine_area, area, 1e-4 * area);
  const auto normals = FaceNormals(mesh), fine_normals = FaceNormals(fine);
  for (size_t f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 4; ++k) EXPECT_GT(fine_normals[4 * f + k].dot(normals[f]), 0.999f);
  // Shared edges split once: the subdivided grid is still a manifold with the same border.
  const VertexAdjacency adj = BuildVertexAdjacency(fine);
  int boundary = 0;
  for (bool b : adj.is_boundary) boundary += b;
  EXPECT_EQ(boundary, 4 * 8);  // 9x9 grid border
  // A flat 4x4 grid of spacing 2 subdivides into the 8x8 grid of spacing 1.
  EXPECT_NEAR(MeanEdgeLength(Subdivide1To4(testing::CreateGridMesh(4, 2.f))),
              MeanEdgeLength(testing::CreateGridMesh(8, 1.f)), 1e-6);
}

TEST(Subdivide1To4, ClosedCubeStaysClosed) {
  const TriangleMesh fine = Subdivide1To4(Subdivide1To4(testing::CreateCube()));
  EXPECT_EQ(fine.num_faces(), 12u * 16u);
  // Euler: V - E + F = 2 for a closed genus-0 surface.
  EXPECT_EQ(long(fine.num_vertices()) - long(UniqueEdges(fine).size()) + long(fine.num_faces()), 2);
  const VertexAdjacency adj = BuildVertexAdjacency(fine);
  EXPECT_TRUE(std::none_of(adj.is_boundary.begin(), adj.is_boundary.end(), [](bool b) { return b; }));
}

// Every edge of a closed mesh is used by exactly two faces (no T-junction, no hole).
void ExpectEveryEdgeUsedTwice(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> uses;
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(f[k], f[(k + 1) % 3])];
  for (const auto& [edge, n] : uses) EXPECT_EQ(n, 2) << edge.first << "-" << edge.second;
}

TEST(SubdivideMarked, AllOrNoneMarkedIsSubdivide1To4OrACopy) {
  const TriangleMesh mesh = testing::CreateGridMesh(4, 2.f, /*wavy=*/true);
  const TriangleMesh all = SubdivideMarked(mesh, std::vector<char>(mesh.num_faces(), 1));
  const TriangleMesh fine = Subdivide1To4(mesh);
  EXPECT_EQ(all.vertices, fine.vertices);
  EXPECT_EQ(all.faces, fine.faces);
  const TriangleMesh none = SubdivideMarked(mesh, std::vector<char>(mesh.num_faces(), 0));
  EXPECT_EQ(none.vertices, mesh.vertices);
  EXPECT_EQ(none.faces, mesh.faces);
}

TEST(SubdivideMarked, OneMarkedFaceOfAClosedCubeStaysClosedAndConforming) {
  const TriangleMesh cube = Subdivide1To4(testing::CreateCube());
  std::vector<char> marked(cube.num_faces(), 0);
  marked[5] = 1;
  const TriangleMesh out = SubdivideMarked(cube, marked);
  // The marked face -> 4, its 3 neighbours bisected -> 2 each: +3 vertices, +3 + 3 faces.
  EXPECT_EQ(out.num_vertices(), cube.num_vertices() + 3);
  EXPECT_EQ(out.num_faces(), cube.num_faces() + 6);
  ExpectEveryEdgeUsedTwice(out);
  EXPECT_EQ(long(out.num_vertices()) - long(UniqueEdges(out).size()) + long(out.num_faces()), 2);
  // Orientation kept: every new face points the way of the face it came from (outward).
  const auto normals = FaceNormals(out);
  for (size_t f = 0; f < out.num_faces(); ++f) {
    Eigen::Vector3f centre = Eigen::Vector3f::Zero();
    for (int k = 0; k < 3; ++k) centre += out.vertices[out.faces[f][k]] / 3.f;
    EXPECT_GT(normals[f].dot(centre - Eigen::Vector3f(0.5f, 0.5f, 0.5f)), 0.f) << "face " << f;
  }
}

TEST(SubdivideMarked, TwoSplitEdgesBecomeThreeAndTheAreaIsKept) {
  // Two marked faces sharing a corner of a third: the closure splits the third wholly
  // when it has two split edges; on a flat grid the area is kept exactly.
  const TriangleMesh mesh = testing::CreateGridMesh(6, 1.f);
  std::vector<char> marked(mesh.num_faces(), 0);
  for (size_t f = 0; f < mesh.num_faces(); f += 7) marked[f] = 1;
  const TriangleMesh out = SubdivideMarked(mesh, marked);
  double area = 0, out_area = 0;
  for (float a : FaceAreas(mesh)) area += a;
  for (float a : FaceAreas(out)) out_area += a;
  EXPECT_NEAR(out_area, area, 1e-5 * area);
  // Conforming: only the grid's border is open (no vertex on another face's edge).
  std::map<std::pair<int, int>, int> uses;
  for (const auto& f : out.faces)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(f[k], f[(k + 1) % 3])];
  for (const auto& [edge, n] : uses) {
    const Eigen::Vector3f a = out.vertices[edge.first], b = out.vertices[edge.second];
    const bool on_border = (a.x() == 0 && b.x() == 0) || (a.y() == 0 && b.y() == 0) ||
                           (a.x() == 6 && b.x() == 6) || (a.y() == 6 && b.y() == 6);
    EXPECT_EQ(n, on_border ? 1 : 2) << a.transpose() << " - " << b.transpose();
  }
  // Every face has 0, 1 or 3 split edges: between 1x and 4x the faces.
  EXPECT_GT(out.num_faces(), mesh.num_faces());
  EXPECT_LT(out.num_faces(), 4 * mesh.num_faces());
}

TEST(MeanEdgeLength, UnitGridCountsEachEdgeOnce) {
  // 1x1 grid: 4 unit edges + 1 diagonal.
  EXPECT_NEAR(MeanEdgeLength(testing::CreateGridMesh(1)), (4 + std::sqrt(2.0)) / 5, 1e-12);
  EXPECT_EQ(MeanEdgeLength(TriangleMesh{}), 0.0);
}

}  // namespace
}  // namespace satmesh
