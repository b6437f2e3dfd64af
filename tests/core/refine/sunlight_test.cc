#include "core/refine/sunlight.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/mesh/topology.h"
#include "core/refine/photometric_gradient.h"
#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

AcquisitionInfo Sun(double elevation_deg, double azimuth_deg) {
  AcquisitionInfo a;
  a.sun_elevation_deg = elevation_deg;
  a.sun_azimuth_deg = azimuth_deg;
  return a;
}

TEST(SunDirection, AzimuthClockwiseFromNorthInTheEastNorthUpFrame) {
  const Eigen::Vector3f east = SunDirection(Sun(45, 90));
  EXPECT_NEAR(east.x(), std::sqrt(0.5), 1e-6);
  EXPECT_NEAR(east.y(), 0, 1e-6);
  EXPECT_NEAR(east.z(), std::sqrt(0.5), 1e-6);
  const Eigen::Vector3f south = SunDirection(Sun(30, 180));
  EXPECT_NEAR(south.y(), -std::cos(30 * M_PI / 180), 1e-6);
  EXPECT_NEAR(south.z(), 0.5, 1e-6);
  EXPECT_EQ(SunDirection(AcquisitionInfo{}), Eigen::Vector3f::Zero());  // not known
  EXPECT_EQ(SunDirection(Sun(-5, 90)), Eigen::Vector3f::Zero());        // below the horizon
}

// Ground z = 0 on [-20, 20]², a canopy 4 m up on [-2, 2]² (faces up): with the sun 45 deg
// high in the east, the canopy's shadow lies 4 m west of it, on [-6, -2] x [-2, 2].
TEST(MarkSunlight, PointsInTheCanopysShadowAreDarkUnderThatSunOnly) {
  TriangleMesh mesh;
  mesh.vertices = {{-20, -20, 0}, {20, -20, 0}, {20, 20, 0}, {-20, 20, 0},
                   {-2, -2, 4},   {2, -2, 4},   {2, 2, 4},   {-2, 2, 4}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  const std::vector<Eigen::Vector3f> normals = FaceNormals(mesh);
  ASSERT_GT(normals[0].z(), 0.99f);
  ASSERT_GT(normals[2].z(), 0.99f);
  // One view whose "pixels" hit these points (the ground's faces 0/1, the canopy's 2).
  const std::vector<SurfacePoint> points = {
      {{-4, 0, 0}, 1},   // in the east sun's shadow
      {{4, 0, 0}, 0},    // east of the canopy: lit
      {{0, 0, 0}, 1},    // under the canopy, but the 45-deg ray leaves beneath its edge
      {{0, 4, 0}, 1},    // north of it: in the south sun's shadow
      {{0.5, 0.5, 4}, 2},  // on the canopy
      {{0, 0, 0}, -1}};  // a pixel that sees nothing
  std::vector<ViewLevel> views(1);
  views[0].view = 0;
  views[0].hit_map.surface = points;
  // Suns: 0 in the east, 1 in the south (shadow north of the canopy), 2 unknown.
  const std::vector<Eigen::Vector3f> suns = {SunDirection(Sun(45, 90)), SunDirection(Sun(45, 180)),
                                             Eigen::Vector3f::Zero()};
  // View 0 is paired with views 1 and 2; a sun only view 3 (not a partner) saw is not traced.
  const std::vector<Eigen::Vector3f> all_suns = {suns[0], suns[1], suns[2], SunDirection(Sun(60, 0))};
  MarkSunlight(mesh, normals, all_suns, {{0, 1}, {2, 0}, {1, 3}}, &views);
  const std::vector<uint64_t>& lit = views[0].hit_map.sunlit;
  ASSERT_EQ(lit.size(), points.size());
  EXPECT_EQ(views[0].hit_map.suns_marked, 0b011u);
  EXPECT_EQ(lit[0], 0b010u);  // dark under the east sun, lit under the south one
  EXPECT_EQ(lit[1], 0b011u);
  EXPECT_EQ(lit[2], 0b011u);
  EXPECT_EQ(lit[3], 0b001u);  // the south sun's shadow falls north of the canopy
  EXPECT_EQ(lit[4], 0b011u);
  EXPECT_EQ(lit[5], 0u);
}

// A pixel lit under one view's sun and dark under the other's is left out of that
// pair-direction, only when both suns are known.
TEST(AccumulatePhotometricGradient, LeavesOutPixelsWhoseLightDiffersBetweenTheSuns) {
  const testing::Plane plane;
  const TriangleMesh mesh = testing::PlaneMesh(plane, 20, 2.0, 0.0);
  const RefineInput input = testing::MakePlaneInput(plane, {{3, 0}, {10, 90}}, mesh, 120, 0.5);
  std::vector<ViewLevel> views;
  for (int v = 0; v < 2; ++v)
    views.push_back(MakeViewLevel(v, 0, NormalizeRadiometry(input.views[v].image),
                                  input.views[v].rpc, input.frame, Eigen::Vector3d(-40, -40, -15),
                                  Eigen::Vector3d(40, 40, 20), 8));
  const RayScene scene(mesh);
  const auto normals = FaceNormals(mesh);
  for (auto& v : views) CastHitMap(scene, &v, &normals);
  PhotometricOptions options;
  options.visibility_tolerance_m = 1.0;
  const auto valid_pixels = [&] {
    return AccumulatePhotometricGradient(views[0], views[1], mesh, normals, options, nullptr,
                                         nullptr)
        .num_valid_pixels;
  };
  const long all = valid_pixels();
  ASSERT_GT(all, 5000);
  // View 0's pixels: even columns lit under view 0's sun only, odd ones under both.
  HitMap& hit_map = views[0].hit_map;
  hit_map.sunlit.resize(hit_map.hits.size());
  for (size_t p = 0; p < hit_map.sunlit.size(); ++p)
    hit_map.sunlit[p] = (p % views[0].width()) % 2 == 0 ? 0b01u : 0b11u;
  hit_map.suns_marked = 0b11u;
  EXPECT_EQ(valid_pixels(), all);  // sunlit_only off
  options.sunlit_only = true;
  const long consistent = valid_pixels();
  EXPECT_NEAR(double(consistent) / double(all), 0.5, 0.02);
  hit_map.suns_marked = 0b01u;  // view 1's sun not known: nothing to compare
  EXPECT_EQ(valid_pixels(), all);
}

}  // namespace
}  // namespace satmesh
