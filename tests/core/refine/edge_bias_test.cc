// Walls moved inward by the photometric term's occluding-edge bias (edge_bias.h), and the
// gradients pooled over patches: one pair's walls, weakly constrained roofs and ground
// (gradient_patch.h).
#include "core/refine/edge_bias.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "core/mesh/topology.h"
#include "core/refine/gradient_patch.h"

namespace satmesh {
namespace {

// A 20 x 20 m ground grid (1 m) with a 6 x 6 x 5 m box on it (x, y in [7, 13]), its walls
// in 1 m columns, all faces sharing their vertices (the ground's border is the mesh's
// only open edge).
TriangleMesh BoxOnGround() {
  TriangleMesh m;
  std::map<std::tuple<int, int, int>, int> index;
  auto v = [&](int x, int y, int z) {
    auto [it, added] = index.try_emplace({x, y, z}, int(m.vertices.size()));
    if (added) m.vertices.emplace_back(float(x), float(y), float(z));
    return it->second;
  };
  auto quad = [&](int a, int b, int c, int d) {  // counter-clockwise seen from outside
    m.faces.emplace_back(a, b, c);
    m.faces.emplace_back(a, c, d);
  };
  auto in_box = [](int x, int y) { return x >= 7 && x < 13 && y >= 7 && y < 13; };
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x) {
      const int z = in_box(x, y) ? 5 : 0;
      quad(v(x, y, z), v(x + 1, y, z), v(x + 1, y + 1, z), v(x, y + 1, z));
    }
  for (int t = 7; t < 13; ++t) {
    quad(v(t, 7, 0), v(t + 1, 7, 0), v(t + 1, 7, 5), v(t, 7, 5));      // south, normal -y
    quad(v(t + 1, 13, 0), v(t, 13, 0), v(t, 13, 5), v(t + 1, 13, 5));  // north, +y
    quad(v(13, t, 0), v(13, t + 1, 0), v(13, t + 1, 5), v(13, t, 5));  // east, +x
    quad(v(7, t + 1, 0), v(7, t, 0), v(7, t, 5), v(7, t + 1, 5));      // west, -x
  }
  return m;
}

TEST(DeflateOccludingEdges, WallsMoveInwardCornersIntoTheCornerTheRestStays) {
  const TriangleMesh before = BoxOnGround();
  TriangleMesh m = before;
  const EdgeBiasStats stats = DeflateOccludingEdges(0.25, &m);
  size_t wall_vertices = 0;
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const Eigen::Vector3f& p = before.vertices[i];
    const Eigen::Vector3f d = m.vertices[i] - p;
    EXPECT_EQ(d.z(), 0.f);
    const bool on_x_wall = (p.x() == 7 || p.x() == 13) && p.y() >= 7 && p.y() <= 13;
    const bool on_y_wall = (p.y() == 7 || p.y() == 13) && p.x() >= 7 && p.x() <= 13;
    // Every wall vertex, top and foot, moves 0.25 m towards the box's inside; at a corner
    // by 0.25 m from each wall.
    const float ex = on_x_wall ? (p.x() == 7 ? 0.25f : -0.25f) : 0.f;
    const float ey = on_y_wall ? (p.y() == 7 ? 0.25f : -0.25f) : 0.f;
    EXPECT_NEAR(d.x(), ex, 1e-5) << p.transpose();
    EXPECT_NEAR(d.y(), ey, 1e-5) << p.transpose();
    wall_vertices += on_x_wall || on_y_wall;
  }
  EXPECT_EQ(wall_vertices, 2u * 24u);  // 24 columns' edges, at the top and at the foot
  EXPECT_EQ(stats.moved, wall_vertices);
  // Outward by the same distance, and back: the surface it started as.
  TriangleMesh fat = before;
  DeflateOccludingEdges(-0.25, &fat);
  DeflateOccludingEdges(0.25, &fat);
  for (size_t i = 0; i < fat.vertices.size(); ++i)
    EXPECT_NEAR((fat.vertices[i] - before.vertices[i]).norm(), 0.f, 1e-5);
  TriangleMesh same = before;
  EXPECT_EQ(DeflateOccludingEdges(0, &same).moved, 0u);
}

// The vertices of wall faces: the box's walls, top and foot, and nothing of the roof's or
// the ground's insides.
TEST(WallVertices, AreTheVerticesOfFacesSteeperThanSixtyDegrees) {
  const TriangleMesh m = BoxOnGround();
  const std::vector<char> on_wall = WallVertices(m);
  ASSERT_EQ(on_wall.size(), m.vertices.size());
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const Eigen::Vector3f& p = m.vertices[i];
    const bool rim = ((p.x() == 7 || p.x() == 13) && p.y() >= 7 && p.y() <= 13) ||
                     ((p.y() == 7 || p.y() == 13) && p.x() >= 7 && p.x() <= 13);
    EXPECT_EQ(bool(on_wall[i]), rim) << p.transpose();
  }
  // A 59-degree slope is not a wall, a 61-degree one is.
  for (const float deg : {59.f, 61.f}) {
    TriangleMesh ramp;
    const float h = std::tan(deg * float(M_PI) / 180.f);
    ramp.vertices = {{0, 0, 0}, {1, 0, h}, {1, 1, h}, {0, 1, 0}};
    ramp.faces = {{0, 1, 2}, {0, 2, 3}};
    const std::vector<char> w = WallVertices(ramp);
    EXPECT_EQ(std::count(w.begin(), w.end(), 1), deg > 60 ? 4 : 0) << deg;
  }
}

// A wall on the mesh's open border (a tile's seam) keeps its place: a tile's neighbour
// meets it there.
TEST(DeflateOccludingEdges, BoundaryVerticesStay) {
  TriangleMesh wall;
  for (int z = 0; z <= 5; z += 5)
    for (int x = 0; x <= 3; ++x) wall.vertices.emplace_back(float(x), 0.f, float(z));
  for (int x = 0; x < 3; ++x) {
    wall.faces.emplace_back(x, x + 1, x + 5);
    wall.faces.emplace_back(x, x + 5, x + 4);
  }
  const TriangleMesh before = wall;
  EXPECT_EQ(DeflateOccludingEdges(0.25, &wall).moved, 0u);
  EXPECT_EQ(wall.vertices, before.vertices);
}


// The east wall's (x = 13) inner vertices, top and foot, and their facing.
bool OnEastWall(const Eigen::Vector3f& p) { return p.x() == 13 && p.y() > 7 && p.y() < 13; }

TEST(WallNormals, FaceOutOfTheBoxAndIntoTheCornerNoneOffTheWalls) {
  const TriangleMesh m = BoxOnGround();
  const std::vector<Eigen::Vector3f> normals = WallNormals(m);
  for (size_t i = 0; i < m.vertices.size(); ++i) {
    const Eigen::Vector3f& p = m.vertices[i];
    const bool x_wall = (p.x() == 7 || p.x() == 13) && p.y() >= 7 && p.y() <= 13;
    const bool y_wall = (p.y() == 7 || p.y() == 13) && p.x() >= 7 && p.x() <= 13;
    const Eigen::Vector3f& n = normals[i];
    if (!x_wall && !y_wall) {
      EXPECT_TRUE(n.isZero()) << p.transpose();
      continue;
    }
    EXPECT_NEAR(n.norm(), 1.f, 1e-5) << p.transpose();
    EXPECT_EQ(n.z(), 0.f);
    const float sx = p.x() == 7 ? -1.f : 1.f, sy = p.y() == 7 ? -1.f : 1.f;
    if (x_wall && y_wall) {  // a corner: out of both walls, by their faces' areas (1:2, 2:1)
      EXPECT_GT(sx * n.x(), 0.44f) << p.transpose();
      EXPECT_GT(sy * n.y(), 0.44f) << p.transpose();
    } else {  // a side: straight out
      EXPECT_NEAR(n.x(), x_wall ? sx : 0.f, 1e-5) << p.transpose();
      EXPECT_NEAR(n.y(), y_wall ? sy : 0.f, 1e-5) << p.transpose();
    }
  }
}

TEST(MakeWallPatches, HoldTheVerticesOfTheSameFacingWithinTheRings) {
  const TriangleMesh m = BoxOnGround();
  const VertexAdjacency adjacency = BuildVertexAdjacency(m);
  const GradientPatches one = MakeWallPatches(m, adjacency, 1);
  const GradientPatches three = MakeWallPatches(m, adjacency, 3);
  const GradientPatches alone = MakeWallPatches(m, adjacency, 0);
  EXPECT_EQ(three.num_directed(), 48u);
  for (size_t v = 0; v < m.vertices.size(); ++v) {
    const int n1 = one.offsets[v + 1] - one.offsets[v];
    const int n3 = three.offsets[v + 1] - three.offsets[v];
    if (three.normal[v].isZero()) {  // roof, ground: no patch
      EXPECT_EQ(n3, 0);
      continue;
    }
    EXPECT_EQ(alone.offsets[v + 1] - alone.offsets[v], 1);
    EXPECT_EQ(three.members[three.offsets[v]], int(v));  // itself first
    for (int k = three.offsets[v]; k < three.offsets[v + 1]; ++k) {
      const int u = three.members[k];
      // Only the same wall: a corner (45 degrees off) joins no side's patch, nor a side a
      // corner's; within 3 edges along the wall.
      EXPECT_GE(three.normal[u].dot(three.normal[v]), 0.79f);
      EXPECT_LE((m.vertices[u] - m.vertices[v]).head<2>().norm(), 3.f + 1e-5f);
    }
    const Eigen::Vector3f& p = m.vertices[v];
    if (OnEastWall(p) && p.y() == 10) {
      // The mid-wall column at y = 10: top and foot of columns 9-11 within 1 edge (the
      // quads' diagonals join the foot of one column to the top of the next); the east
      // wall's inner vertices (y 8-12, top and foot) all within 3, and no more than its
      // corners beside them.
      EXPECT_GE(n1, 4);
      EXPECT_LE(n1, 5);
      int inner = 0;
      for (int k = three.offsets[v]; k < three.offsets[v + 1]; ++k)
        inner += OnEastWall(m.vertices[three.members[k]]);
      EXPECT_EQ(inner, 10);
      EXPECT_LE(n3, 14);
    }
  }
}

TEST(PoolPatchGradients, AgreeingWallsStepAsOnePatchNoiseKeepsEachVertexOwn) {
  const TriangleMesh m = BoxOnGround();
  const GradientPatches patches = MakeWallPatches(m, BuildVertexAdjacency(m), 3);
  const size_t nv = m.vertices.size();
  // Across the east wall (its corners too where they lean east) every vertex says "out" by 1
  // (and something along the wall and up, which stays); every other wall's vertices
  // alternate +1 / -1 along their normal (no direction beyond their noise); roof and ground
  // vertices have gradients of their own.
  std::vector<Eigen::Vector3d> gradient(nv);
  for (size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3f& p = m.vertices[v];
    if (patches.normal[v].x() > 0.79f) gradient[v] = Eigen::Vector3d(1.0, 0.3, -0.2);
    else if (!patches.normal[v].isZero())
      gradient[v] = (int(p.x() + p.y() + p.z()) % 2 ? 1.0 : -1.0) * patches.normal[v].cast<double>();
    else gradient[v] = Eigen::Vector3d(0.1 * double(v % 7), 0.2, -0.3);
  }
  std::vector<Eigen::Vector3d> pooled = gradient;
  const size_t replaced = PoolPatchGradients(patches, &pooled);
  EXPECT_GE(replaced, 10u);  // the east wall's ten inner vertices (and corners leaning east)
  for (size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3f& p = m.vertices[v];
    if (OnEastWall(p)) {
      const double n = patches.offsets[v + 1] - patches.offsets[v];
      EXPECT_NEAR(pooled[v].x(), std::sqrt(n), 1e-9);  // sqrt(n) x the mean, 1
      EXPECT_EQ(pooled[v].y(), 0.3);
      EXPECT_EQ(pooled[v].z(), -0.2);
    } else if (patches.normal[v].isZero() ||
               ((p.x() == 7 || p.y() == 7) && patches.normal[v].x() <= 0)) {
      // roof, ground, and the west and south walls (but a corner leaning east), whose
      // patches are noise
      EXPECT_EQ(pooled[v], gradient[v]) << p.transpose();
    }
  }
}

// The gate: a patch whose mean is within 2 standard errors of zero leaves its vertex's own
// component (at 1 standard error a third of the patches with no direction would pass and
// move a wall as one); beyond 2 it is replaced. The east wall's inner vertices across it
// 0.65 +-1 (alternating), its corners and the other walls 0.
TEST(PoolPatchGradients, OnlyBeyondTwoStandardErrors) {
  const TriangleMesh m = BoxOnGround();
  const GradientPatches patches = MakeWallPatches(m, BuildVertexAdjacency(m), 4);
  const size_t nv = m.vertices.size();
  std::vector<Eigen::Vector3d> gradient(nv, Eigen::Vector3d::Zero());
  for (size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3f& p = m.vertices[v];
    if (OnEastWall(p)) gradient[v].x() = 0.65 + (int(p.y() + p.z()) % 2 ? 1.0 : -1.0);
  }
  std::vector<Eigen::Vector3d> pooled = gradient;
  PoolPatchGradients(patches, &pooled);
  int between = 0, beyond = 0;
  for (size_t v = 0; v < nv; ++v) {
    if (!OnEastWall(m.vertices[v])) continue;
    const Eigen::Vector3d h = patches.normal[v].cast<double>();
    double sum = 0, sum2 = 0;
    const int begin = patches.offsets[v], end = patches.offsets[v + 1];
    for (int k = begin; k < end; ++k) {
      const double x = gradient[patches.members[k]].dot(h);
      sum += x, sum2 += x * x;
    }
    const double n = end - begin, mean = sum / n;
    const double z = std::abs(mean) / std::sqrt((sum2 - n * mean * mean) / (n - 1) / n);
    if (z >= 2) {
      ++beyond;
      EXPECT_NEAR(pooled[v].dot(h), std::sqrt(n) * mean, 1e-9) << m.vertices[v].transpose();
    } else {
      between += z >= 1;
      EXPECT_EQ(pooled[v], gradient[v]) << m.vertices[v].transpose() << " z " << z;
    }
  }
  EXPECT_GT(beyond, 0);
  EXPECT_GT(between, 0);  // patches 1-2 standard errors out: the test tells 1 from 2
}

// Roof patches: a roof or ground vertex whose pull weight is at least 0.5 (its images
// constrain it less than the initial surface does) pools its plane's gradients along its
// normal; one the images constrain, and every wall vertex, keeps its own.
TEST(MakeRoofPatches, WeakVerticesPoolTheirPlaneOthersKeepTheirOwn) {
  const TriangleMesh m = BoxOnGround();
  const size_t nv = m.vertices.size();
  const GradientPatches walls = MakeWallPatches(m, BuildVertexAdjacency(m), 0);
  // The roof's inner vertices (x, y in 8-12) weak but for x = 12 (0.49, just under); the
  // ground weak at x < 3, constrained elsewhere; the walls' vertices weak too.
  std::vector<float> prior_weight(nv, 0.f);
  for (size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3f& p = m.vertices[v];
    if (p.z() == 5) prior_weight[v] = p.x() == 12 ? 0.49f : 0.5f;
    if (p.z() == 0 && p.x() < 3) prior_weight[v] = 1.f;
    if (!walls.normal[v].isZero()) prior_weight[v] = 1.f;
  }
  const GradientPatches roofs = MakeRoofPatches(m, BuildVertexAdjacency(m), 2, prior_weight);
  EXPECT_EQ(walls.step_factor, 1.0);
  EXPECT_EQ(roofs.step_factor, kRoofPatchStepFactor);
  std::vector<Eigen::Vector3d> gradient(nv);
  for (size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3f& p = m.vertices[v];
    // The roof says "down" by 1 (and something sideways, which stays); the ground
    // alternates +-1 (noise).
    gradient[v] = p.z() == 5 ? Eigen::Vector3d(0.2, -0.1, 1.0)
                             : Eigen::Vector3d(0, 0, int(p.x() + p.y()) % 2 ? 1.0 : -1.0);
  }
  std::vector<Eigen::Vector3d> pooled = gradient;
  const size_t replaced = PoolPatchGradients(roofs, &pooled);
  EXPECT_EQ(replaced, 20u);  // the roof's inner 5 x 5 but x = 12
  for (size_t v = 0; v < nv; ++v) {
    const Eigen::Vector3f& p = m.vertices[v];
    const int n = roofs.offsets[v + 1] - roofs.offsets[v];
    if (!walls.normal[v].isZero()) {  // a wall's vertex: no direction, no patch
      EXPECT_TRUE(roofs.normal[v].isZero());
      EXPECT_EQ(pooled[v], gradient[v]);
      continue;
    }
    EXPECT_NEAR(roofs.normal[v].z(), 1.f, 1e-6);
    if (p.z() == 5 && p.x() < 12) {
      for (int k = roofs.offsets[v]; k < roofs.offsets[v + 1]; ++k) {
        const Eigen::Vector3f& q = m.vertices[roofs.members[k]];
        EXPECT_EQ(q.z(), 5.f);  // its plane: not the ground beyond the walls
        EXPECT_LE((q - p).cwiseAbs().maxCoeff(), 2.f);
      }
      if (p.x() == 10 && p.y() == 10) {
        EXPECT_EQ(n, 19);  // 1 + 6 + 12 within 2 edges
      }
      // half a wall's step: 0.5 sqrt(n) x the mean, 1
      EXPECT_NEAR(pooled[v].z(), 0.5 * std::sqrt(double(n)), 1e-9) << p.transpose();
      EXPECT_EQ(pooled[v].x(), 0.2);
      EXPECT_EQ(pooled[v].y(), -0.1);
    } else {
      // x = 12 on the roof (constrained), the constrained ground: no patch; the weak ground
      // at x < 3: a patch of noise
      EXPECT_EQ(n == 0, p.z() == 5 || p.x() >= 3) << p.transpose();
      EXPECT_EQ(pooled[v], gradient[v]) << p.transpose();
    }
  }
}

}  // namespace
}  // namespace satmesh
