// Walls hung plumb under their tops (plumb_walls.h): the walk up a DSM's sloped wall, and
// how far each of its vertices lies outside the vertical through the top.
#include "core/refine/plumb_walls.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "core/mesh/topology.h"

namespace satmesh {
namespace {

// A DSM's grid as a mesh: heights z(x, y) at 0.5 m over [0, 10] x [0, 10] m, two triangles
// per cell. Vertex (i, j) is at (0.5 i, 0.5 j) and has index j * 21 + i.
constexpr int kN = 21;
int At(int i, int j) { return j * kN + i; }

TriangleMesh GridMesh(const std::function<float(int, int)>& z) {
  TriangleMesh m;
  for (int j = 0; j < kN; ++j)
    for (int i = 0; i < kN; ++i) m.vertices.emplace_back(0.5f * i, 0.5f * j, z(i, j));
  for (int j = 0; j + 1 < kN; ++j)
    for (int i = 0; i + 1 < kN; ++i) {
      m.faces.emplace_back(At(i, j), At(i + 1, j), At(i + 1, j + 1));
      m.faces.emplace_back(At(i, j), At(i + 1, j + 1), At(i, j + 1));
    }
  return m;
}

// A roof 6 m up over x <= 5 m whose east wall a DSM holds as a slope: 3 m up at x = 5.5,
// the ground at x = 6.
float SlopedWall(int i, int) { return i <= 10 ? 6.f : i == 11 ? 3.f : 0.f; }

TEST(MakePlumbLines, ASlopedWallsVerticesHangFromTheRoofEdgeAbove) {
  const TriangleMesh m = GridMesh(SlopedWall);
  const PlumbLines lines = MakePlumbLines(m, BuildVertexAdjacency(m));
  for (int j = 2; j < kN - 2; ++j) {  // away from the grid's border
    // The foot and the middle of the slope hang from the roof's edge vertex in their row,
    // 1 and 0.5 m inside them.
    for (int i : {11, 12}) {
      ASSERT_EQ(lines.top[At(i, j)], At(10, j)) << i << " " << j;
      EXPECT_NEAR(lines.normal[At(i, j)].x(), 1.0, 1e-3);
      EXPECT_NEAR(PlumbOffsets(lines, m.vertices)[At(i, j)], 0.5 * (i - 10), 1e-5);
    }
    // The edge is its wall's top; the roof and the ground beyond the foot are no wall.
    EXPECT_EQ(lines.top[At(10, j)], -1);
    EXPECT_EQ(PlumbOffsets(lines, m.vertices)[At(10, j)], 0.0);
    for (int i : {2, 9, 13, 18}) EXPECT_EQ(lines.top[At(i, j)], -1) << i;
  }
  EXPECT_EQ(lines.num_hung(), size_t(2 * kN));
}

TEST(MakePlumbLines, AWallEndsAtItsOwnTopNotAHigherOneBeyondALowerRoof) {
  // Ground, a lower roof 3 m up over x in [3, 6.5] m, the upper roof 8 m up over x <= 2.5
  // m; both walls sloped over one cell: the lower wall's vertices hang from the lower roof's
  // edge (no steep edge crosses the lower roof), the upper's from the upper roof's.
  const TriangleMesh m = GridMesh([](int i, int) {
    return i <= 5 ? 8.f : i == 6 ? 5.5f : i <= 13 ? 3.f : i == 14 ? 1.5f : 0.f;
  });
  const PlumbLines lines = MakePlumbLines(m, BuildVertexAdjacency(m));
  const int j = 10;
  EXPECT_EQ(lines.top[At(6, j)], At(5, j));
  EXPECT_EQ(lines.top[At(7, j)], At(5, j));
  EXPECT_NEAR(PlumbOffsets(lines, m.vertices)[At(7, j)], 1.0, 1e-5);
  EXPECT_EQ(lines.top[At(8, j)], -1);  // the lower roof
  EXPECT_EQ(lines.top[At(13, j)], -1);
  EXPECT_EQ(lines.top[At(14, j)], At(13, j));
  EXPECT_EQ(lines.top[At(15, j)], At(13, j));
  EXPECT_NEAR(PlumbOffsets(lines, m.vertices)[At(15, j)], 1.0, 1e-5);
}

TEST(MakePlumbLines, TheWalkStopsWhereTheRiseEasesBelowSeventyDegrees) {
  // The sloped wall with a rounded shoulder behind its edge: 1 m up over the next 0.5 m
  // (63 degrees), then the roof. The wall's top is the edge at x = 5 m, not the shoulder.
  const TriangleMesh m = GridMesh([](int i, int j) { return i <= 9 ? 7.f : SlopedWall(i, j); });
  const PlumbLines lines = MakePlumbLines(m, BuildVertexAdjacency(m));
  const int j = 10;
  EXPECT_EQ(lines.top[At(12, j)], At(10, j));
  EXPECT_EQ(lines.top[At(11, j)], At(10, j));
  EXPECT_EQ(lines.top[At(10, j)], -1);
  // Steeper than 70 degrees (1.5 m over 0.5 m: 71.6), the shoulder is the wall's.
  const TriangleMesh steep =
      GridMesh([](int i, int j) { return i <= 9 ? 7.5f : SlopedWall(i, j); });
  EXPECT_EQ(MakePlumbLines(steep, BuildVertexAdjacency(steep)).top[At(12, j)], At(9, j));
}

TEST(PlumbOffsets, NegativeInsideTheTopsVerticalZeroOnIt) {
  // The sloped wall's foot moved 1.2 m in (under an eave): 0.2 m inside the top's vertical;
  // on it: 0.
  TriangleMesh m = GridMesh(SlopedWall);
  const PlumbLines lines = MakePlumbLines(m, BuildVertexAdjacency(m));
  const int foot = At(12, 10), middle = At(11, 10);
  m.vertices[foot].x() -= 1.2f;
  EXPECT_NEAR(PlumbOffsets(lines, m.vertices)[foot], -0.2, 1e-5);
  m.vertices[middle].x() -= 0.5f;
  EXPECT_NEAR(PlumbOffsets(lines, m.vertices)[middle], 0.0, 1e-5);
}

TEST(MakePlumbLines, GentleSlopesAndFlatGroundHangNothing) {
  // A 40-degree roof pitch and flat ground: no face steeper than 60 degrees, no wall.
  const TriangleMesh m = GridMesh([](int i, int) { return 0.5f * i * std::tan(40 * M_PI / 180); });
  const PlumbLines lines = MakePlumbLines(m, BuildVertexAdjacency(m));
  EXPECT_EQ(lines.num_hung(), 0u);
}

}  // namespace
}  // namespace satmesh
