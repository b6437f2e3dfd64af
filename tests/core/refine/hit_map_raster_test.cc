#include "core/refine/hit_map_raster.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/image/image.h"
#include "core/mesh/topology.h"
#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

// A tilted plane with a 3 m block (steep walls: occlusion edges in oblique views), made
// of triangles of `spacing` metres, slightly jittered so no edge is axis-aligned.
TriangleMesh BlockMesh(double spacing_m) {
  TriangleMesh mesh = testing::PlaneMesh(testing::Plane{}, 20, spacing_m, 0.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jitter(-0.1f * float(spacing_m), 0.1f * float(spacing_m));
  for (auto& p : mesh.vertices) {
    p.x() += jitter(rng), p.y() += jitter(rng);
    if (std::abs(p.x()) < 5.5f && std::abs(p.y()) < 5.5f) p.z() += 3.f;
  }
  return mesh;
}

struct Agreement {
  long both = 0, hit_mismatch = 0, same_face = 0, close = 0, close_t = 0;
};

// Rasterized vs ray-cast hit maps of one view (0.5 m GSD, oblique by off_nadir_deg).
Agreement CompareWithRaycast(const TriangleMesh& mesh, double off_nadir_deg) {
  const RefineInput input =
      testing::MakePlaneInput(testing::Plane{}, {{off_nadir_deg, 40}}, mesh, 120, 0.5);
  auto make_view = [&] {
    return MakeViewLevel(0, 0, NormalizeRadiometry(input.views[0].image), input.views[0].rpc,
                         input.frame, Eigen::Vector3d(-30, -30, -15), Eigen::Vector3d(30, 30, 20), 8);
  };
  ViewLevel cast = make_view(), raster = make_view();
  RayScene scene(mesh);
  CastHitMap(scene, &cast);
  RasterWorkspace workspace;
  RasterizeHitMap(mesh, &raster, &workspace);

  Agreement a;
  for (size_t p = 0; p < cast.hit_map.hits.size(); ++p) {
    const RayHit &c = cast.hit_map.hits[p], &r = raster.hit_map.hits[p];
    EXPECT_EQ(raster.hit_map.surface[p].face, r.face);
    if (c.hit() != r.hit()) ++a.hit_mismatch;
    if (!c.hit() || !r.hit()) continue;
    ++a.both;
    a.same_face += c.face == r.face;
    a.close += (cast.hit_map.surface[p].point - raster.hit_map.surface[p].point).norm() < 0.005f;
    a.close_t += std::abs(c.t - r.t) < 0.005f;  // unit directions: t in metres
  }
  std::printf("both hit %ld, hit mismatch %ld, same face %.5f, points within 5 mm %.5f\n", a.both,
              a.hit_mismatch, double(a.same_face) / a.both, double(a.close) / a.both);
  return a;
}

// The rasterized hit map is Embree's: hit where it hits (but for pixel centres on an
// edge), the same face, the same point (walls' edges aside) and, with check_t, the same
// ray parameter.
void ExpectAgreement(const Agreement& a, bool check_t) {
  ASSERT_GT(a.both, 5000);
  EXPECT_LT(double(a.hit_mismatch) / a.both, 0.001);
  EXPECT_GT(double(a.same_face) / a.both, 0.998);
  EXPECT_GT(double(a.close) / a.both, 0.998);
  if (check_t) EXPECT_GT(double(a.close_t) / a.both, 0.998);
}

TEST(RasterizeHitMap, AgreesWithEmbreeRayCastingAtTwoPixelsATriangle) {
  ExpectAgreement(CompareWithRaycast(BlockMesh(1.0), 25), /*check_t=*/true);
}

// Triangles of ~3 pixels: boxes of 2, 3 and 4 pixel centres a side, so faces of one batch
// of 8 go to the AVX2 path at 2 x 2 and 3 x 3 centres and to the scalar one, side by side.
TEST(RasterizeHitMap, AgreesWithEmbreeWhereTheVectorAndScalarPathsMeet) {
  ExpectAgreement(CompareWithRaycast(BlockMesh(1.4), 30), /*check_t=*/true);
}

TEST(RasterizeHitMap, AgreesWithEmbreeOnLargeTrianglesAndSteepViews) {
  ExpectAgreement(CompareWithRaycast(BlockMesh(4.0), 35), /*check_t=*/false);
}

// Under a curved RFM the rasterized hit points are the RFM's own answer: each reprojects
// (exact RPC) onto its pixel centre, closer than the virtual camera's straight rays that
// Embree traces (their approximation error has its own test in virtual_camera_test).
TEST(RasterizeHitMap, HitPointsReprojectOntoTheirPixelsUnderACubicRfm) {
  const TriangleMesh mesh = BlockMesh(1.0);
  const LocalFrame frame(Eigen::Vector3d(5.44, 43.26, 100.0));
  const RpcModel rpc = testing::CurvedRpc(frame, {25, 40}, 0.5, 160);
  const RpcModel affine = testing::AffineRpc(frame, {25, 40}, 0.5, 160);
  const Eigen::Vector3d corner = frame.GeoFromLocal(Eigen::Vector3d(35, 35, 10));
  const double curvature_px = (rpc.PixelFromGeo(corner) - affine.PixelFromGeo(corner)).norm();
  EXPECT_GT(curvature_px, 0.05);  // the cubic and denominator terms matter
  auto make_view = [&] {
    return MakeViewLevel(0, 0, ImageF(160, 160), rpc, frame, Eigen::Vector3d(-30, -30, -15),
                         Eigen::Vector3d(30, 30, 20), 8);
  };
  ViewLevel cast = make_view(), raster = make_view();
  RayScene scene(mesh);
  CastHitMap(scene, &cast);
  RasterWorkspace workspace;
  RasterizeHitMap(mesh, &raster, &workspace);
  std::vector<double> err_cast, err_raster;
  long both = 0, same_face = 0;
  for (size_t p = 0; p < cast.hit_map.hits.size(); ++p) {
    if (!cast.hit_map.hits[p].hit() || !raster.hit_map.hits[p].hit()) continue;
    ++both;
    same_face += cast.hit_map.surface[p].face == raster.hit_map.surface[p].face;
    const Eigen::Vector2d centre(p % 160 + 0.5, p / 160 + 0.5);
    auto error = [&](const Eigen::Vector3f& X) {
      return (rpc.PixelFromGeo(frame.GeoFromLocal(X.cast<double>())) - centre).norm();
    };
    err_cast.push_back(error(cast.hit_map.surface[p].point));
    err_raster.push_back(error(raster.hit_map.surface[p].point));
  }
  std::sort(err_cast.begin(), err_cast.end());
  std::sort(err_raster.begin(), err_raster.end());
  const double median_cast = err_cast[err_cast.size() / 2], median_raster = err_raster[err_raster.size() / 2];
  std::printf("curvature %.3f px; reprojection error median / max: raster %.4f / %.4f px, "
              "ray casting %.4f / %.4f px; same face %.4f of %ld\n",
              curvature_px, median_raster, err_raster.back(), median_cast, err_cast.back(),
              double(same_face) / both, both);
  ASSERT_GT(both, 5000);
  EXPECT_LT(median_raster, 0.005);
  EXPECT_LT(err_raster.back(), 0.02);
  EXPECT_LT(median_raster, median_cast);
  EXPECT_GT(double(same_face) / both, 0.9);  // the rest: the rays' error moves them a face over
}

TEST(RasterizeHitMap, SkipsFacesWithNonFiniteVertices) {
  const TriangleMesh clean = BlockMesh(1.0);
  TriangleMesh broken = clean;
  for (int k = 0; k < 50; ++k) broken.vertices[k * 7].x() = std::numeric_limits<float>::quiet_NaN();
  const RefineInput input = testing::MakePlaneInput(testing::Plane{}, {{20, 0}}, clean, 120, 0.5);
  auto count_hits = [&](const TriangleMesh& mesh) {
    ViewLevel view = MakeViewLevel(0, 0, NormalizeRadiometry(input.views[0].image),
                                   input.views[0].rpc, input.frame, Eigen::Vector3d(-30, -30, -15),
                                   Eigen::Vector3d(30, 30, 20), 8);
    RasterWorkspace workspace;
    RasterizeHitMap(mesh, &view, &workspace);
    long hits = 0;
    for (size_t p = 0; p < view.hit_map.hits.size(); ++p) {
      const RayHit& hit = view.hit_map.hits[p];
      if (!hit.hit()) continue;
      ++hits;
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(mesh.vertices[mesh.faces[hit.face][k]].allFinite());
      EXPECT_TRUE(view.hit_map.surface[p].point.allFinite());
    }
    return hits;
  };
  const long clean_hits = count_hits(clean), broken_hits = count_hits(broken);
  std::printf("hits: clean mesh %ld, with 50 NaN vertices %ld\n", clean_hits, broken_hits);
  EXPECT_GT(clean_hits, 5000);
  EXPECT_LT(broken_hits, clean_hits);             // the NaN vertices' faces are gone
  EXPECT_GT(broken_hits, 0.9 * clean_hits);       // and nothing else
}

// Between rasterizations a pixel keeps its face; its point moves along the pixel's ray
// onto the face's moved plane. Moved by a typical iteration's step (here up to 0.05 m =
// 0.1 GSD, in z and sideways), the followed points are a fresh rasterization's wherever
// the ray still crosses the same face (median 0.0000 m; moved with the face at its
// barycentrics instead, 0.018 m), nearly all of them; unmoved, they are the
// rasterization's to float rounding.
TEST(FollowHitMaps, PointsMoveWithTheirFacesCloseToAFreshRasterization) {
  const TriangleMesh mesh = BlockMesh(1.0);
  const RefineInput input = testing::MakePlaneInput(testing::Plane{}, {{25, 40}}, mesh, 120, 0.5);
  auto make_views = [&] {
    std::vector<ViewLevel> views;
    views.push_back(MakeViewLevel(0, 0, NormalizeRadiometry(input.views[0].image),
                                  input.views[0].rpc, input.frame, Eigen::Vector3d(-30, -30, -15),
                                  Eigen::Vector3d(30, 30, 20), 8));
    return views;
  };
  HitMapScratch scratch;
  std::vector<ViewLevel> followed = make_views(), fresh = make_views();
  const auto normals = FaceNormals(mesh);
  RasterizeHitMaps(mesh, &followed, &scratch, &normals);
  RasterizeHitMaps(mesh, &fresh, &scratch, &normals);
  FollowHitMaps(mesh, &followed, &scratch, &normals);  // nothing moved: the same hit map
  const HitMap &a = followed[0].hit_map, &b = fresh[0].hit_map;
  for (size_t p = 0; p < a.hits.size(); ++p) {
    ASSERT_EQ(a.surface[p].face, b.surface[p].face);
    if (a.surface[p].face < 0) continue;
    ASSERT_LT((a.surface[p].point - b.surface[p].point).norm(), 1e-4f);
    ASSERT_EQ(a.ray_cos[p], b.ray_cos[p]);
    ASSERT_NEAR(a.hits[p].t, b.hits[p].t, 1e-4f);
  }

  TriangleMesh moved = mesh;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> step(-0.03f, 0.03f);
  for (auto& v : moved.vertices) v += Eigen::Vector3f(step(rng), step(rng), 0.02f + step(rng));
  const auto moved_normals = FaceNormals(moved);
  FollowHitMaps(moved, &followed, &scratch, &moved_normals);
  RasterizeHitMaps(moved, &fresh, &scratch, &moved_normals);
  long both = 0, same_face = 0, close = 0, cos_close = 0;
  std::vector<float> distance;
  for (size_t p = 0; p < a.hits.size(); ++p) {
    if (a.surface[p].face < 0 || b.surface[p].face < 0) continue;
    ++both;
    same_face += a.surface[p].face == b.surface[p].face;
    distance.push_back((a.surface[p].point - b.surface[p].point).norm());
    close += distance.back() < 0.06f;  // the largest vertex move
    cos_close += std::abs(a.ray_cos[p] - b.ray_cos[p]) < 0.02f;
    EXPECT_NEAR(a.ray_cos[p], followed[0].ray_directions[p].dot(moved_normals[a.surface[p].face]),
                1e-6f);
  }
  std::sort(distance.begin(), distance.end());
  const float median = distance[distance.size() / 2];
  std::printf("followed vs fresh: same face %.4f, point distance median %.4f m, p98 %.4f m, "
              "within 6 cm %.4f, ray cosines within 0.02 %.4f of %ld\n",
              double(same_face) / both, median, distance[distance.size() * 98 / 100],
              double(close) / both, double(cos_close) / both, both);
  ASSERT_GT(both, 5000);
  EXPECT_GT(double(same_face) / both, 0.9);
  EXPECT_GT(double(close) / both, 0.98);
  EXPECT_LT(median, 0.001f);  // on the ray: a fiftieth of the largest move
  EXPECT_GT(double(cos_close) / both, 0.95);
}

// pairs_per_iteration: an iteration updates only its pairs' views. A view kept keeps its
// hit map as it was; one rasterized or followed through UpdateHitMaps gets what updating
// it alone gives.
TEST(UpdateHitMaps, OnlyTheChosenViewsAreUpdated) {
  const TriangleMesh mesh = BlockMesh(1.0);
  const RefineInput input =
      testing::MakePlaneInput(testing::Plane{}, {{25, 40}, {20, 200}}, mesh, 120, 0.5);
  auto make_views = [&] {
    std::vector<ViewLevel> views;
    for (int v = 0; v < 2; ++v)
      views.push_back(MakeViewLevel(v, 0, NormalizeRadiometry(input.views[v].image),
                                    input.views[v].rpc, input.frame,
                                    Eigen::Vector3d(-30, -30, -15), Eigen::Vector3d(30, 30, 20), 8));
    return views;
  };
  auto same = [](const HitMap& a, const HitMap& b) {
    if (a.hits.size() != b.hits.size()) return false;
    long hits = 0;
    for (size_t p = 0; p < a.hits.size(); ++p) {
      if (a.surface[p].face != b.surface[p].face) return false;
      if (a.surface[p].face < 0) continue;
      ++hits;
      if (a.surface[p].point != b.surface[p].point || a.ray_cos[p] != b.ray_cos[p]) return false;
    }
    return hits > 5000;
  };
  HitMapScratch scratch;
  const auto normals = FaceNormals(mesh);
  std::vector<ViewLevel> views = make_views(), before = make_views(), fresh = make_views();
  RasterizeHitMaps(mesh, &views, &scratch, &normals);
  RasterizeHitMaps(mesh, &before, &scratch, &normals);

  TriangleMesh moved = mesh;
  for (auto& v : moved.vertices) v += Eigen::Vector3f(0.01f * v.y(), 0.0f, 0.3f + 0.02f * v.x());
  const auto moved_normals = FaceNormals(moved);
  RasterizeHitMaps(moved, &fresh, &scratch, &moved_normals);
  using U = HitMapUpdate;
  UpdateHitMaps(moved, &views, &scratch, &moved_normals, {U::kRasterize, U::kKeep});
  EXPECT_TRUE(same(views[0].hit_map, fresh[0].hit_map));
  EXPECT_TRUE(same(views[1].hit_map, before[1].hit_map));
  EXPECT_FALSE(same(views[1].hit_map, fresh[1].hit_map));  // the move is seen

  std::vector<ViewLevel> followed = make_views();
  RasterizeHitMaps(mesh, &followed, &scratch, &normals);
  FollowHitMaps(moved, &followed, &scratch, &moved_normals);  // both, as the reference
  UpdateHitMaps(moved, &views, &scratch, &moved_normals, {U::kKeep, U::kFollow});
  EXPECT_TRUE(same(views[0].hit_map, fresh[0].hit_map));  // left as rasterized above
  EXPECT_TRUE(same(views[1].hit_map, followed[1].hit_map));
}

}  // namespace
}  // namespace satmesh
