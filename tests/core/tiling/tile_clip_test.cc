#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <map>

#include "core/tiling/tile_run.h"

namespace satmesh {
namespace {

// A wavy n x n grid of unit cells from (0, 0), two triangles per cell.
PointMesh GridMesh(int n) {
  PointMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.points.emplace_back(i, j, std::sin(0.7 * i) + 0.3 * j);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.faces.emplace_back(a, b, d);
      m.faces.emplace_back(a, d, c);
    }
  }
  return m;
}

double AreaXy(const PointMesh& m) {
  double area = 0;
  for (const auto& f : m.faces) {
    const Eigen::Vector3d e1 = m.points[f[1]] - m.points[f[0]], e2 = m.points[f[2]] - m.points[f[0]];
    area += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
  }
  return area;
}

TEST(ClipToBox, KeepsExactlyTheBoxArea) {
  const PointMesh mesh = GridMesh(10);
  const Box2d box{2.3, 1.7, 6.05, 8.4};
  const PointMesh piece = ClipToBox(mesh, box);
  EXPECT_NEAR(AreaXy(piece), box.width() * box.height(), 1e-9);
  for (const auto& p : piece.points) EXPECT_TRUE(box.Contains(p.x(), p.y())) << p.transpose();
}

TEST(ClipToBox, NeighboursMeetWithoutGapOrOverlap) {
  const PointMesh mesh = GridMesh(10);
  const PointMesh west = ClipToBox(mesh, {0, 0, 4.5, 10}), east = ClipToBox(mesh, {4.5, 0, 10, 10});
  EXPECT_NEAR(AreaXy(west) + AreaXy(east), 100.0, 1e-9);
  // Every vertex on the shared edge of one piece is a vertex of the other, same height.
  std::map<double, double> west_edge, east_edge;
  for (const auto& p : west.points) if (p.x() == 4.5) west_edge[p.y()] = p.z();
  for (const auto& p : east.points) if (p.x() == 4.5) east_edge[p.y()] = p.z();
  EXPECT_EQ(west_edge.size(), 21u);  // 11 grid rows + 10 diagonals cut
  EXPECT_EQ(west_edge, east_edge);
}

TEST(ClipToBox, SharedCutsAreOneVertexAndInsideFacesAreKept) {
  const PointMesh mesh = GridMesh(4);
  const PointMesh all = ClipToBox(mesh, {-1, -1, 5, 5});
  EXPECT_EQ(all.faces.size(), mesh.faces.size());
  EXPECT_EQ(all.points.size(), mesh.points.size());
  const PointMesh half = ClipToBox(mesh, {0, 0, 2.5, 4});
  // Column x = 2.5 cuts 4 horizontal edges... 5 vertical-grid rows and 4 diagonals: 9 new
  // vertices, shared by the faces on both sides of each cut edge.
  EXPECT_EQ(half.points.size(), 15u + 9u);
  EXPECT_TRUE(ClipToBox(mesh, {10, 10, 12, 12}).faces.empty());
}

// A per-point height sigma is carried by the kept points and interpolated along the cut
// edges like the coordinates: sigma = x here, so every point's sigma equals its x.
TEST(ClipToBox, CarriesHeightSigmaInterpolatedAtTheCuts) {
  PointMesh m = GridMesh(6);
  for (const auto& p : m.points) m.height_sigma.push_back(float(p.x()));
  const PointMesh out = ClipToBox(m, Box2d{1.3, 0.7, 4.6, 5.2});
  ASSERT_EQ(out.height_sigma.size(), out.points.size());
  for (size_t i = 0; i < out.points.size(); ++i)
    EXPECT_NEAR(out.height_sigma[i], out.points[i].x(), 1e-5) << i;
  EXPECT_TRUE(ClipToBox(GridMesh(6), Box2d{1.3, 0.7, 4.6, 5.2}).height_sigma.empty());
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

double Area3d(const PointMesh& m) {
  double area = 0;
  for (const auto& f : m.faces)
    area += 0.5 * (m.points[f[1]] - m.points[f[0]]).cross(m.points[f[2]] - m.points[f[0]]).norm();
  return area;
}

// Quad a, b, c, d (counter-clockwise) as two triangles.
void AddQuad(PointMesh* m, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
             const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  const int base = int(m->points.size());
  for (const auto& p : {a, b, c, d}) m->points.push_back(p);
  m->faces.emplace_back(base, base + 1, base + 2);
  m->faces.emplace_back(base, base + 2, base + 3);
}

TEST(ClipToBox, KeepsWallsAndOverhangsIn3d) {
  PointMesh m;
  AddQuad(&m, {0, 5, 0}, {10, 5, 0}, {10, 5, 6}, {0, 5, 6});  // wall, 10 m x 6 m
  AddQuad(&m, {0, 5, 4}, {10, 5, 4}, {10, 7, 4}, {0, 7, 4});  // balcony slab at 4 m
  const PointMesh piece = ClipToBox(m, Box2d{2.5, 0, 7.5, 10});
  EXPECT_NEAR(Area3d(piece), 5 * 6 + 5 * 2, 1e-9);  // half of each, nothing flattened
  double zmax = 0;
  for (const auto& p : piece.points) zmax = std::max(zmax, p.z());
  EXPECT_EQ(zmax, 6);
}

TEST(ClipToBox, AWallOnASharedEdgeGoesToOneTile) {
  PointMesh m;
  AddQuad(&m, {5, 0, 0}, {5, 10, 0}, {5, 10, 6}, {5, 0, 6});  // in the plane x = 5
  const size_t west = ClipToBox(m, Box2d{0, 0, 5, 10}).faces.size();
  const size_t east = ClipToBox(m, Box2d{5, 0, 10, 10}).faces.size();
  EXPECT_EQ(west + east, 2u);
  EXPECT_EQ(east, 2u);  // tiles own their west and south edges
}

TEST(ClipToBox, CutsNextToVerticesLeaveNoDebris) {
  // Box edges 0.05 mm from grid vertices: the cut points there are those vertices.
  const PointMesh mesh = GridMesh(10);
  const Box2d box{2.00005, 1.99995, 7.99995, 8.00005};
  MeshDebris before;
  CleanPointMesh(ClipToBox(mesh, box, MeshCleanOptions{1e-9, 1e-9}), {}, &before);
  EXPECT_GT(before.Total(), 0u) << "the case does not make debris without cleaning";
  MeshDebris after;
  const PointMesh piece = ClipToBox(mesh, box);
  CleanPointMesh(piece, {}, &after);
  EXPECT_EQ(after.Total(), 0u) << after.ToString();
  EXPECT_NEAR(AreaXy(piece), box.width() * box.height(), 1e-3);
}

}  // namespace
}  // namespace satmesh
