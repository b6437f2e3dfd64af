// Exact pushbroom camera, RPC fit and GDAL's RPC transformer, straight-line rays.
#include <gdal.h>
#include <gdal_alg.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/geo/crs.h"
#include "core/rpc/rpc_fit.h"
#include "core/rpc/rpc_io.h"
#include "core/synth/geodesy.h"
#include "core/synth/pushbroom_camera.h"
#include "core/synth/render.h"
#include "core/synth/scene_files.h"

namespace satmesh::synth {
namespace {

const Eigen::Vector3d kCenter(-81.6557, 30.3322, 5.0);
constexpr double kHalfDeg = 0.0006;  // ~60 m

PushbroomCamera TestCamera(double off_nadir, double azimuth) {
  ViewGeometrySetup s;
  s.center_lon_lat_h = kCenter;
  s.off_nadir_deg = off_nadir;
  s.azimuth_deg = azimuth;
  std::vector<Eigen::Vector3d> cover;
  for (double dx : {-kHalfDeg, kHalfDeg})
    for (double dy : {-kHalfDeg, kHalfDeg})
      for (double h : {-30.0, 45.0}) cover.emplace_back(kCenter.x() + dx, kCenter.y() + dy, h);
  return PushbroomCamera::LookingAt(s, cover);
}

TEST(Geodesy, RoundTrip) {
  for (const Eigen::Vector3d g : {Eigen::Vector3d(-81.6, 30.3, -25), Eigen::Vector3d(5.4, 43.3, 600e3),
                                  Eigen::Vector3d(120, -60, 1000)}) {
    const Eigen::Vector3d back = GeoFromEcef(EcefFromGeo(g));
    EXPECT_NEAR(back.x(), g.x(), 1e-11);
    EXPECT_NEAR(back.y(), g.y(), 1e-11);
    EXPECT_NEAR(back.z(), g.z(), 1e-6);
  }
}

TEST(PushbroomCamera, CenterAngleAndRoundTrip) {
  const PushbroomCamera cam = TestCamera(30, 120);
  auto c = cam.PixelFromGeo(kCenter);
  ASSERT_TRUE(c.has_value());
  EXPECT_NEAR(c->x(), cam.params().col_center, 1e-6);
  EXPECT_NEAR(c->y(), cam.params().row_center, 1e-6);
  // Set up with the ellipsoid normal; measured against the geocentric nadir.
  EXPECT_NEAR(cam.OffNadirDeg(kCenter), 30.0, 0.2);
  EXPECT_NEAR(cam.SatelliteAzimuthZenithDeg(kCenter).x(), 120.0, 1e-6);
  const double gsd = cam.GroundGsdM(kCenter);
  EXPECT_GT(gsd, 0.3);
  EXPECT_LT(gsd, 0.5);
  EXPECT_GT(cam.width(), 60 / 0.5);
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d px(u(gen) * cam.width(), u(gen) * cam.height());
    const double h = -30 + 75 * u(gen);
    auto g = cam.LocalizeAtHeight(px, h);
    ASSERT_TRUE(g.has_value());
    EXPECT_NEAR(g->z(), h, 1e-6);
    auto back = cam.PixelFromGeo(*g);
    ASSERT_TRUE(back.has_value());
    EXPECT_LT((*back - px).norm(), 1e-6);
  }
}

TEST(RpcFit, HalfStepGridBelowHundredthPixel) {
  for (double on : {5.0, 20.0, 35.0}) {
    const PushbroomCamera cam = TestCamera(on, 40 + 3 * on);
    const RpcFitResult fit = FitRpc(
        [&](const Eigen::Vector3d& g) { return *cam.PixelFromGeo(g); },
        kCenter - Eigen::Vector3d(kHalfDeg, kHalfDeg, 35), kCenter + Eigen::Vector3d(kHalfDeg, kHalfDeg, 40));
    EXPECT_LT(fit.max_px_half_step, 0.01) << "off-nadir " << on;
    // Independent random check.
    std::mt19937 gen(7);
    std::uniform_real_distribution<double> u(-1, 1);
    double worst = 0;
    for (int k = 0; k < 200; ++k) {
      const Eigen::Vector3d g = kCenter + Eigen::Vector3d(u(gen) * kHalfDeg, u(gen) * kHalfDeg, 2.5 + 37 * u(gen));
      worst = std::max(worst, (fit.model.PixelFromGeo(g) - *cam.PixelFromGeo(g)).norm());
    }
    EXPECT_LT(worst, 0.01) << "off-nadir " << on;
  }
}

TEST(RpcFit, GdalRpcTransformerAgreesWithExactCamera) {
  const PushbroomCamera cam = TestCamera(25, 250);
  const RpcFitResult fit = FitRpc(
      [&](const Eigen::Vector3d& g) { return *cam.PixelFromGeo(g); },
      kCenter - Eigen::Vector3d(kHalfDeg, kHalfDeg, 35), kCenter + Eigen::Vector3d(kHalfDeg, kHalfDeg, 40));
  const std::string path = (std::filesystem::temp_directory_path() / "synth_rpc_test.tif").string();
  WriteImageWithRpc(path, ImageF(cam.width(), cam.height(), 100.f), fit.model);
  EXPECT_LT((ReadRpc(path).PixelFromGeo(kCenter) - *cam.PixelFromGeo(kCenter)).norm(), 1e-6);
  GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
  ASSERT_NE(ds, nullptr);
  GDALRPCInfoV2 info;
  ASSERT_TRUE(GDALExtractRPCInfoV2(GDALGetMetadata(ds, "RPC"), &info));
  void* tr = GDALCreateRPCTransformerV2(&info, FALSE, 0.001, nullptr);
  ASSERT_NE(tr, nullptr);
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d g = kCenter + Eigen::Vector3d(u(gen) * kHalfDeg, u(gen) * kHalfDeg, 2.5 + 37 * u(gen));
    double x = g.x(), y = g.y(), z = g.z();
    int ok = 0;
    GDALRPCTransform(tr, TRUE, 1, &x, &y, &z, &ok);  // geo -> pixel
    ASSERT_TRUE(ok);
    worst = std::max(worst, (Eigen::Vector2d(x, y) - *cam.PixelFromGeo(g)).norm());
  }
  EXPECT_LT(worst, 0.01);
  GDALDestroyRPCTransformer(tr);
  GDALClose(ds);
  std::filesystem::remove(path);
}

TEST(ViewRayGrid, StraightLineRaysBelowHundredthPixel) {
  const PushbroomCamera cam = TestCamera(35, 300);
  const Eigen::Vector3d utm = CrsTransform(kWgs84Geographic3D, "EPSG:32617").Apply(kCenter);
  const Eigen::Vector3d origin(std::round(utm.x()), std::round(utm.y()), -24);
  ViewRayGrid::Options o;
  o.h_low_m = -40, o.h_high_m = 50;
  const ViewRayGrid rays(cam, "EPSG:32617", origin, o);
  EXPECT_LT(RayGridErrorPx(cam, rays, "EPSG:32617", origin, {-30, 5, 45}, 7), 0.01);
}

}  // namespace
}  // namespace satmesh::synth
