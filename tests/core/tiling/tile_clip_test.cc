#include <gtest/gtest.h>

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
