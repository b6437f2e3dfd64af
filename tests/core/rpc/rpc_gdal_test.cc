// RpcModel against GDAL's own RPC transformer, and ReadRpc through GDAL's "RPC" domain.
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal.h>
#include <gdal_alg.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <vector>

#include "core/common/error.h"
#include "core/rpc/rpc_io.h"
#include "tests/core/rpc/test_cameras.h"

namespace satmesh {
namespace {

// GDAL's forward transform (no DEM) of lon/lat/h points to (pixel, line).
std::vector<Eigen::Vector2d> GdalProject(const std::string& path,
                                         const std::vector<Eigen::Vector3d>& geo) {
  GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
  EXPECT_NE(ds, nullptr);
  GDALRPCInfoV2 info;
  EXPECT_TRUE(GDALExtractRPCInfoV2(GDALGetMetadata(ds, "RPC"), &info));
  void* transformer = GDALCreateRPCTransformerV2(&info, /*bReversed=*/FALSE, 0.0, nullptr);
  GDALClose(ds);
  std::vector<double> x, y, z;
  for (const auto& g : geo) x.push_back(g.x()), y.push_back(g.y()), z.push_back(g.z());
  std::vector<int> ok(geo.size());
  GDALRPCTransform(transformer, /*bDstToSrc=*/TRUE, static_cast<int>(geo.size()), x.data(),
                   y.data(), z.data(), ok.data());
  GDALDestroyRPCTransformer(transformer);
  std::vector<Eigen::Vector2d> out;
  for (size_t i = 0; i < geo.size(); ++i) {
    EXPECT_TRUE(ok[i]);
    out.emplace_back(x[i], y[i]);
  }
  return out;
}

// Ground points of a pixel grid over the image at several heights (by our localisation).
std::vector<Eigen::Vector3d> FootprintPoints(const RpcModel& m, double size_px, double h0, double h1) {
  std::vector<Eigen::Vector3d> out;
  for (double h : {h0, 0.5 * (h0 + h1), h1})
    for (double r = 0; r <= size_px; r += size_px / 8)
      for (double c = 0; c <= size_px; c += size_px / 8) {
        const auto ll = m.LocalizeLonLat({c, r}, h);
        EXPECT_TRUE(ll.has_value());
        if (ll) out.emplace_back(ll->x(), ll->y(), h);
      }
  return out;
}

double MaxDifferenceToGdal(const RpcModel& m, const std::string& path,
                           const std::vector<Eigen::Vector3d>& geo) {
  const std::vector<Eigen::Vector2d> gdal = GdalProject(path, geo);
  double worst = 0;
  for (size_t i = 0; i < geo.size(); ++i) worst = std::max(worst, (m.PixelFromGeo(geo[i]) - gdal[i]).norm());
  return worst;
}

TEST(GdalRpcTransformer, PixelIsSampPlusHalf) {
  // Identity-like RPC: samp = L * SAMP_SCALE + SAMP_OFF. At the offsets samp = SAMP_OFF
  // exactly, and GDAL 3.6 returns pixel = SAMP_OFF + 0.5 (same for the line).
  RpcCoefficients c;
  c.samp_off = 100, c.line_off = 200, c.samp_scale = 1000, c.line_scale = 1000;
  c.long_off = 5, c.lat_off = 43, c.long_scale = 0.01, c.lat_scale = 0.01, c.height_scale = 100;
  c.samp_num[1] = 1, c.line_num[2] = -1, c.samp_den[0] = 1, c.line_den[0] = 1;
  const RpcModel m = RpcModel::FromCoefficients(c);
  const std::string path = "/vsimem/rpc_gdal_test_half.tif";
  test::WriteRpcGeoTiff(path, m.ToKeyValues());
  const auto gdal = GdalProject(path, {{5, 43, 0}, {5.005, 42.995, 30}});
  EXPECT_NEAR(gdal[0].x(), 100.5, 1e-9);
  EXPECT_NEAR(gdal[0].y(), 200.5, 1e-9);
  EXPECT_NEAR(gdal[1].x(), 600.5, 1e-6);
  EXPECT_NEAR(gdal[1].y(), 700.5, 1e-6);
  EXPECT_LT((m.PixelFromGeo({5, 43, 0}) - gdal[0]).norm(), 1e-9);
  VSIUnlink(path.c_str());
}

TEST(ReadRpc, GeoTiffTagsRoundTrip) {
  const RpcModel m = test::FitPushbroom({}).model;
  const std::string path = "/vsimem/rpc_gdal_test_tags.tif";
  test::WriteRpcGeoTiff(path, m.ToKeyValues());
  const RpcModel back = ReadRpc(path);
  for (const auto& g : FootprintPoints(m, 2000, 0, 100))
    EXPECT_LT((back.PixelFromGeo(g) - m.PixelFromGeo(g)).norm(), 1e-8);
  VSIUnlink(path.c_str());
}

TEST(ReadRpc, RpbSidecar) {
  const RpcModel m = test::FitPushbroom({}).model;
  const std::string dir = ::testing::TempDir() + "/rpc_gdal_test_rpb";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/image.tif";
  const char* options[] = {"PROFILE=BASELINE", "RPB=YES", nullptr};
  test::WriteRpcGeoTiff(path, m.ToKeyValues(), options);
  ASSERT_TRUE(std::filesystem::exists(dir + "/image.RPB"));
  const RpcModel back = ReadRpc(path);
  for (const auto& g : FootprintPoints(m, 2000, 0, 100))
    EXPECT_LT((back.PixelFromGeo(g) - m.PixelFromGeo(g)).norm(), 1e-6);
  std::filesystem::remove_all(dir);
}

TEST(ReadRpc, MissingFileIsNotFound) {
  try {
    ReadRpc("/nonexistent/image.tif");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/image.tif"), std::string::npos);
  }
}

TEST(ReadRpc, ImageWithoutRpcIsInvalid) {
  const std::string path = "/vsimem/rpc_gdal_test_none.tif";
  test::WriteRpcGeoTiff(path, {});
  try {
    ReadRpc(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  VSIUnlink(path.c_str());
}

// WorldView/Pléiades-like RPCs (fitted to pushbroom cameras), written into GeoTIFFs.
TEST(RpcModel, MatchesGdalTransformerOnSyntheticRpcs) {
  const double zeniths[] = {5, 20, 35}, azimuths[] = {100, 10, 235};
  for (int i = 0; i < 3; ++i) {
    test::PushbroomParams p;
    p.zenith_deg = zeniths[i], p.azimuth_deg = azimuths[i];
    const std::string path = "/vsimem/rpc_gdal_test_" + std::to_string(i) + ".tif";
    test::WriteRpcGeoTiff(path, test::FitPushbroom(p).model.ToKeyValues());
    const RpcModel m = ReadRpc(path);
    const double worst = MaxDifferenceToGdal(m, path, FootprintPoints(m, 2000, -20, 150));
    std::printf("zenith %.0f: max |ours - GDAL| = %.2e px\n", zeniths[i], worst);
    EXPECT_LT(worst, 1e-6);
    VSIUnlink(path.c_str());
  }
}

// The real Pléiades triplet (shared data; skipped when absent).
TEST(RpcModel, MatchesGdalTransformerOnPleiades) {
  const std::string dir = std::string(SATMESH_SHARED_DATA_DIR) + "/pleiades_marseille_triplet";
  if (!std::filesystem::exists(dir + "/img_01.tif")) GTEST_SKIP() << "no shared data at " << dir;
  for (const char* name : {"img_01.tif", "img_02.tif", "img_03.tif"}) {
    const std::string path = dir + "/" + name;
    const RpcModel m = ReadRpc(path);
    const auto geo = FootprintPoints(m, 1024, 0, 400);
    const double worst = MaxDifferenceToGdal(m, path, geo);
    std::printf("%s: max |ours - GDAL| = %.2e px\n", name, worst);
    EXPECT_LT(worst, 1e-6) << name;
    // Localisation round trip and Jacobian on the real model too.
    for (const auto& g : geo) {
      Eigen::Matrix<double, 2, 3> j;
      const Eigen::Vector2d px = m.PixelFromGeo(g, &j);
      const auto ll = m.LocalizeLonLat(px, g.z());
      ASSERT_TRUE(ll.has_value());
      EXPECT_LT((m.PixelFromGeo({ll->x(), ll->y(), g.z()}) - px).norm(), 1e-6);
      const double step_h = 1e-3 * m.coefficients().height_scale;
      const Eigen::Vector2d fd = (m.PixelFromGeo(g + Eigen::Vector3d(0, 0, step_h)) -
                                  m.PixelFromGeo(g - Eigen::Vector3d(0, 0, step_h))) / (2 * step_h);
      EXPECT_LT((fd - j.col(2)).norm(), 1e-6 * j.col(2).norm());
    }
  }
}

}  // namespace
}  // namespace satmesh
