#include "core/eval/mesh_metrics.h"

#include <gtest/gtest.h>

#include "core/common/error.h"

#include <random>

namespace satmesh {
namespace {

// 20 m x 20 m ground (1 m grid, hole under the building) + a 6x6x5 m box building
// (4 walls + roof). Facade area 120 m^2, roof 36, ground 364.
TriangleMesh MakeBoxScene() {
  TriangleMesh m;
  m.origin = {500000.0, 4000000.0, 50.0};
  auto add = [&](float x, float y, float z) {
    m.vertices.emplace_back(x, y, z);
    return int(m.vertices.size()) - 1;
  };
  auto quad = [&](int a, int b, int c, int d) {
    m.faces.emplace_back(a, b, c);
    m.faces.emplace_back(a, c, d);
  };
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 20; ++x) {
      if (x >= 7 && x < 13 && y >= 7 && y < 13) continue;
      quad(add(x, y, 0), add(x + 1, y, 0), add(x + 1, y + 1, 0), add(x, y + 1, 0));
    }
  const int b0 = add(7, 7, 0), b1 = add(13, 7, 0), b2 = add(13, 13, 0), b3 = add(7, 13, 0);
  const int t0 = add(7, 7, 5), t1 = add(13, 7, 5), t2 = add(13, 13, 5), t3 = add(7, 13, 5);
  quad(b0, b1, t1, t0);
  quad(b1, b2, t2, t1);
  quad(b2, b3, t3, t2);
  quad(b3, b0, t0, t3);
  quad(t0, t1, t2, t3);
  return m;
}

TEST(SampleSurface, DensityAndFacadeClassification) {
  const TriangleMesh mesh = MakeBoxScene();
  SampleOptions o;
  o.samples_per_m2 = 8;
  const SurfaceSamples s = SampleSurface(mesh, o);
  EXPECT_NEAR(double(s.points.size()), 520.0 * 8, 0.03 * 520 * 8);
  size_t facade = 0;
  for (const auto& n : s.normals) facade += IsFacadeNormal(n, 0.3);
  EXPECT_NEAR(double(facade) / s.points.size(), 120.0 / 520.0, 0.02);
  EXPECT_TRUE(IsFacadeNormal({1, 0, 0}, 0.3));
  EXPECT_TRUE(IsFacadeNormal({0.96f, 0, 0.28f}, 0.3));
  EXPECT_FALSE(IsFacadeNormal({0, 0, -1}, 0.3));
  EXPECT_FALSE(IsFacadeNormal({0.7f, 0, 0.714f}, 0.3));
  for (const auto& p : s.points) {  // absolute coordinates
    EXPECT_GE(p.x(), 500000.0);
    EXPECT_LE(p.x(), 500020.0);
  }
}

TEST(SurfaceDistance, BackendsAgreeWithKnownDistances) {
  const TriangleMesh mesh = MakeBoxScene();
  std::vector<Eigen::Vector3d> pts{mesh.origin + Eigen::Vector3d(3.3, 4.1, 0.7),    // 0.7 above ground
                                   mesh.origin + Eigen::Vector3d(10, 10, 5.25),     // 0.25 above roof
                                   mesh.origin + Eigen::Vector3d(6.6, 10, 2.0),     // 0.4 off a wall
                                   mesh.origin + Eigen::Vector3d(13.3, 13.4, 5.0)};  // 0.5 off a corner
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2, 22);
  for (int k = 0; k < 200; ++k) pts.push_back(mesh.origin + Eigen::Vector3d(u(rng), u(rng), u(rng) / 3));
  const auto cgal = SurfaceDistance(mesh, DistanceBackend::kCgalAabb).Distances(pts, 1e9);
  const auto embree = SurfaceDistance(mesh, DistanceBackend::kEmbree).Distances(pts, 1e9);
  EXPECT_NEAR(cgal[0], 0.7, 1e-5);
  EXPECT_NEAR(cgal[1], 0.25, 1e-5);
  EXPECT_NEAR(cgal[2], 0.4, 1e-5);
  EXPECT_NEAR(cgal[3], 0.5, 1e-5);
  for (size_t k = 0; k < pts.size(); ++k) EXPECT_NEAR(cgal[k], embree[k], 1e-4) << k;
  // With a cap, far points report >= the cap.
  const auto capped = SurfaceDistance(mesh, DistanceBackend::kEmbree).Distances(pts, 0.3);
  for (size_t k = 0; k < pts.size(); ++k) {
    if (cgal[k] < 0.3f) EXPECT_NEAR(capped[k], cgal[k], 1e-4);
    else EXPECT_GE(capped[k], 0.3f);
  }
}

TEST(EvaluateMesh3d, SelfIsPerfect) {
  const TriangleMesh mesh = MakeBoxScene();
  const Mesh3dMetrics m = EvaluateMesh3d(mesh, mesh);
  ASSERT_EQ(m.all.thresholds_m.size(), 3u);
  for (size_t t = 0; t < 3; ++t) {
    EXPECT_DOUBLE_EQ(m.all.accuracy[t], 1.0);
    EXPECT_DOUBLE_EQ(m.all.completeness[t], 1.0);
    EXPECT_DOUBLE_EQ(m.all.fscore[t], 1.0);
    EXPECT_DOUBLE_EQ(m.facade.accuracy[t], 1.0);
    EXPECT_DOUBLE_EQ(m.facade.completeness[t], 1.0);
  }
  EXPECT_GT(m.facade.num_truth_samples, 400u);  // ~120 m^2 * 4
  EXPECT_LT(m.facade.num_truth_samples, m.all.num_truth_samples / 3);
}

TEST(EvaluateMesh3d, VerticalShiftFallsBetweenThresholds) {
  const TriangleMesh truth = MakeBoxScene();
  TriangleMesh shifted = truth;
  shifted.origin.z() += 0.4;
  for (auto backend : {DistanceBackend::kEmbree, DistanceBackend::kCgalAabb}) {
    Mesh3dOptions o;
    o.backend = backend;
    const Mesh3dMetrics m = EvaluateMesh3d(shifted, truth, o);
    // Horizontal surfaces are 0.4 m off: out at 0.3 m, in at 0.5 m. Walls stay on their
    // planes, so at 0.3 m about the facade share (120/520) plus a sliver near walls passes.
    EXPECT_GT(m.all.accuracy[0], 0.2);
    EXPECT_LT(m.all.accuracy[0], 0.3);
    EXPECT_DOUBLE_EQ(m.all.accuracy[1], 1.0);
    EXPECT_DOUBLE_EQ(m.all.completeness[1], 1.0);
    EXPECT_DOUBLE_EQ(m.all.fscore[2], 1.0);
    // Facades: only the top 0.1 m of the raised walls (over 5 m) is > 0.3 m away.
    EXPECT_NEAR(m.facade.accuracy[0], 0.98, 0.015);
    EXPECT_NEAR(m.facade.completeness[0], 0.98, 0.015);
  }
}

TEST(EvaluateMesh3d, CropAndOptions) {
  const TriangleMesh mesh = MakeBoxScene();
  Mesh3dOptions o;
  o.crop_xmin = 500000.0;
  o.crop_xmax = 500005.0;  // ground only
  o.crop_ymin = 4000000.0;
  o.crop_ymax = 4000020.0;
  const Mesh3dMetrics m = EvaluateMesh3d(mesh, mesh, o);
  EXPECT_NEAR(double(m.all.num_truth_samples), 100.0 * 4, 60);
  EXPECT_EQ(m.facade.num_truth_samples, 0u);
  EXPECT_EQ(Mesh3dOptions{}.Check(), "");
  o.thresholds_m = {0.3, -1};
  EXPECT_NE(o.Check().find("thresholds_m"), std::string::npos);
  EXPECT_THROW(EvaluateMesh3d(mesh, mesh, o), Error);
}

TEST(FacadeOffsets, SignFollowsWhichSideOfTheTrueWallTheResultLies) {
  const TriangleMesh truth = MakeBoxScene();
  // The building (its last 8 vertices) scaled about its axis: walls `d` m out (d > 0) or in.
  auto scaled = [&](float d) {
    TriangleMesh m = truth;
    for (size_t i = m.vertices.size() - 8; i < m.vertices.size(); ++i) {
      auto& v = m.vertices[i];
      v.x() = 10 + (v.x() - 10) * (3 + d) / 3;
      v.y() = 10 + (v.y() - 10) * (3 + d) / 3;
    }
    return m;
  };
  const FacadeOffsets out = EvaluateMesh3d(scaled(0.4f), truth).facade_offset;
  EXPECT_EQ(out.max_offset_m, 3.0);
  EXPECT_NEAR(out.median_m, 0.4, 0.01);
  EXPECT_NEAR(out.p25_m, 0.4, 0.01);
  EXPECT_NEAR(out.p75_m, 0.4, 0.01);
  EXPECT_DOUBLE_EQ(out.outside_fraction, 0.0);  // 0.4 m out is near, not "outside"
  EXPECT_GT(double(out.num_crossed), 0.97 * double(out.num_samples));
  EXPECT_NEAR(double(out.num_samples), 120.0 * 4, 0.1 * 120 * 4);  // 4 samples per m^2
  // 0.6 m in: each wall's 0.6 m at both ends looks past the shrunk building (20%).
  const FacadeOffsets in = EvaluateMesh3d(scaled(-0.6f), truth).facade_offset;
  EXPECT_NEAR(in.median_m, -0.6, 0.01);
  EXPECT_NEAR(in.inside_fraction, 0.8, 0.05);
  EXPECT_NEAR(double(in.num_crossed) / double(in.num_samples), 0.8, 0.05);
  EXPECT_DOUBLE_EQ(in.outside_fraction, 0.0);
  // Beyond max_offset_m nothing is crossed; the flags must match the samples.
  const SurfaceSamples samples = SampleSurface(truth);
  std::vector<uint8_t> facade(samples.points.size());
  for (size_t k = 0; k < facade.size(); ++k) facade[k] = IsFacadeNormal(samples.normals[k], 0.3);
  EXPECT_EQ(MeasureFacadeOffsets(scaled(0.4f), samples, facade, 0.3).num_crossed, 0u);
  EXPECT_THROW(MeasureFacadeOffsets(truth, samples, {}, 3.0), Error);
  EXPECT_THROW(MeasureFacadeOffsets(truth, samples, facade, 0.0), Error);
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

TEST(UnderOverhang, GroundUnderASlabIsCoveredWallsAndRoofsAreNot) {
  TriangleMesh m = MakeBoxScene();
  // A 2 m deep balcony slab (both faces) along the building's south wall, 3 m up.
  const auto add = [&](float x, float y, float z) {
    m.vertices.emplace_back(x, y, z);
    return int(m.vertices.size()) - 1;
  };
  const int a = add(7, 5, 3), b = add(13, 5, 3), c = add(13, 7, 3), d = add(7, 7, 3);
  m.faces.emplace_back(a, b, c);  // top
  m.faces.emplace_back(a, c, d);
  m.faces.emplace_back(a, c, b);  // underside
  m.faces.emplace_back(a, d, c);
  SampleOptions options;
  options.samples_per_m2 = 20;
  const SurfaceSamples s = SampleSurface(m, options);
  const std::vector<uint8_t> covered = UnderOverhang(m, s);
  size_t ground_under = 0, ground_under_covered = 0, others_covered = 0, wall_above_covered = 0;
  for (size_t k = 0; k < s.points.size(); ++k) {
    const Eigen::Vector3d p = s.points[k] - m.origin;
    const bool under_slab = p.x() > 7.01 && p.x() < 12.99 && p.y() > 5.01 && p.y() < 6.99;
    if (std::abs(p.z()) < 1e-3 && under_slab) ++ground_under, ground_under_covered += covered[k];
    else if (std::abs(p.z()) < 1e-3 && !(p.x() > 6.9 && p.x() < 13.1 && p.y() > 4.9 && p.y() < 7.1)) others_covered += covered[k];
    // The south wall above the slab, and the roof, have nothing above them.
    if (std::abs(p.y() - 7) < 1e-3 && p.z() > 3.2) wall_above_covered += covered[k];
    if (std::abs(p.z() - 5) < 1e-3) others_covered += covered[k];
  }
  EXPECT_GT(ground_under, 100u);
  EXPECT_EQ(ground_under_covered, ground_under);
  EXPECT_EQ(others_covered, 0u);
  EXPECT_EQ(wall_above_covered, 0u);
  // The truth against itself: every covered sample is found.
  const Mesh3dMetrics self = EvaluateMesh3d(m, m);
  EXPECT_GT(self.under_overhang.num_truth_samples, 50u);
  EXPECT_DOUBLE_EQ(self.under_overhang.completeness[0], 1.0);
}

// Views as constant directions towards their sensors (a satellite is far: over 20 m the
// direction turns by micro-radians), from off-nadir and azimuth (clockwise from north, +y).
Eigen::Vector3f Towards(double off_nadir_deg, double azimuth_deg) {
  const double z = off_nadir_deg * M_PI / 180, a = azimuth_deg * M_PI / 180;
  return Eigen::Vector3f(float(std::sin(z) * std::sin(a)), float(std::sin(z) * std::cos(a)),
                         float(std::cos(z)));
}

ViewDirectionsFn ConstantViews(const std::vector<Eigen::Vector3f>& towards) {
  return [towards](const std::vector<Eigen::Vector3d>& points) {
    ViewDirections d;
    for (const auto& t : towards) d.emplace_back(points.size(), t);
    return d;
  };
}

TEST(SeenByViews, TwoViewsFacingAWallSeeItAndAnOccluderHidesItsFoot) {
  TriangleMesh m = MakeBoxScene();
  // A 6 m high screen 1 m north of the building's north wall (y = 13), both sides.
  const int base = int(m.vertices.size());
  for (const Eigen::Vector3f& p : {Eigen::Vector3f(5, 14, 0), Eigen::Vector3f(15, 14, 0),
                                   Eigen::Vector3f(15, 14, 6), Eigen::Vector3f(5, 14, 6)})
    m.vertices.push_back(p);
  m.faces.emplace_back(base, base + 1, base + 2);
  m.faces.emplace_back(base, base + 2, base + 3);
  m.faces.emplace_back(base, base + 2, base + 1);
  m.faces.emplace_back(base, base + 3, base + 2);
  SampleOptions options;
  options.samples_per_m2 = 40;
  const SurfaceSamples s = SampleSurface(m, options);
  // Two sensors to the north (30 and 20 degrees off nadir) and one to the east.
  const ViewDirectionsFn views = ConstantViews({Towards(30, 0), Towards(20, 0), Towards(30, 90)});
  const std::vector<uint8_t> seen = SeenByViews(m, s, views(s.points));
  // A north-wall point at height z (its ray starts 0.05 m off the wall) clears the
  // screen's top in the 30-degree view where z + 0.95 / tan(60 deg) > 6 (z > 4.36), in
  // the 20-degree view where z > 3.39: both see it above 4.36. The east wall is seen by one view only, the south wall by none.
  size_t north_high = 0, north_high_seen = 0, north_low_seen = 0, east = 0, east_seen = 0,
         south_seen = 0;
  for (size_t k = 0; k < s.points.size(); ++k) {
    const Eigen::Vector3d p = s.points[k] - m.origin;
    if (std::abs(p.y() - 13) < 1e-3 && p.x() > 7 && p.x() < 13) {
      if (p.z() > 4.4) ++north_high, north_high_seen += seen[k];
      if (p.z() < 4.3) north_low_seen += seen[k];
    }
    if (std::abs(p.x() - 13) < 1e-3 && p.y() > 7 && p.y() < 13) ++east, east_seen += seen[k];
    if (std::abs(p.y() - 7) < 1e-3 && p.x() > 7 && p.x() < 13) south_seen += seen[k];
  }
  EXPECT_GT(north_high, 100u);
  EXPECT_EQ(north_high_seen, north_high);
  EXPECT_EQ(north_low_seen, 0u);
  EXPECT_GT(east, 1000u);
  EXPECT_EQ(east_seen, 0u);
  EXPECT_EQ(south_seen, 0u);
  // The screen removed, the north wall is seen by both north views; a 4-view minimum
  // or a grazing threshold above the views' cosine (sin 20 deg = 0.34) loses it again.
  const TriangleMesh box = MakeBoxScene();
  const SurfaceSamples b = SampleSurface(box, options);
  const ViewDirections d = views(b.points);
  auto count_north = [&](const std::vector<uint8_t>& sel) {
    size_t n = 0;
    for (size_t k = 0; k < b.points.size(); ++k) {
      const Eigen::Vector3d p = b.points[k] - box.origin;
      if (std::abs(p.y() - 13) < 1e-3 && p.x() > 7 && p.x() < 13) n += sel[k];
    }
    return n;
  };
  size_t box_north = 0;
  for (size_t k = 0; k < b.points.size(); ++k) {
    const Eigen::Vector3d p = b.points[k] - box.origin;
    box_north += std::abs(p.y() - 13) < 1e-3 && p.x() > 7 && p.x() < 13;
  }
  EXPECT_GT(box_north, 1000u);
  EXPECT_EQ(count_north(SeenByViews(box, b, d)), box_north);
  EXPECT_EQ(count_north(SeenByViews(box, b, d, 4)), 0u);
  EXPECT_EQ(count_north(SeenByViews(box, b, d, 2, 0.4)), 0u);
  // A view the sample falls outside of (zero direction) does not count.
  ViewDirections outside = d;
  std::fill(outside[1].begin(), outside[1].end(), Eigen::Vector3f::Zero());
  EXPECT_EQ(count_north(SeenByViews(box, b, outside)), 0u);
}

TEST(EvaluateMesh3d, SeenFacadesAreTheWallsTwoViewsSee) {
  const TriangleMesh truth = MakeBoxScene();
  const ViewDirectionsFn views = ConstantViews({Towards(30, 0), Towards(20, 0), Towards(30, 90)});
  const Mesh3dMetrics self = EvaluateMesh3d(truth, truth, {}, &views);
  // Only the north wall: 30 of the 120 m^2 of facades.
  EXPECT_NEAR(double(self.seen_facade.num_truth_samples) / self.facade.num_truth_samples, 0.25, 0.03);
  EXPECT_DOUBLE_EQ(self.seen_facade.completeness[1], 1.0);
  // The building (its last 8 vertices) 0.7 m east: the north wall, the one seen, slides
  // along itself and stays; the east and west walls are lost at 0.5 m. 0.7 m north: the
  // north wall is lost but for the bands within 0.5 m of the roof, the ground and the
  // side walls' ends (10 + 10 + 17%).
  auto moved = [&](const Eigen::Vector3f& shift) {
    TriangleMesh m = truth;
    for (size_t i = m.vertices.size() - 8; i < m.vertices.size(); ++i) m.vertices[i] += shift;
    return EvaluateMesh3d(m, truth, {}, &views);
  };
  const Mesh3dMetrics east = moved({0.7f, 0, 0});
  EXPECT_GT(east.seen_facade.completeness[1], 0.9);
  EXPECT_LT(east.facade.completeness[1], 0.75);
  const Mesh3dMetrics north = moved({0, 0.7f, 0});
  EXPECT_LT(north.seen_facade.completeness[1], 0.45);
  // Without views: no seen facades.
  EXPECT_TRUE(EvaluateMesh3d(truth, truth).seen_facade.thresholds_m.empty());
}

}  // namespace
}  // namespace satmesh
