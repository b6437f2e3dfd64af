#include "core/geo/crs.h"

#include <gtest/gtest.h>

#include "core/common/error.h"

namespace satmesh {
namespace {

TEST(CrsTransform, UtmWgs84RoundTripKeepsHeight) {
  const CrsTransform utm_from_geo(kWgs84Geographic3D, "EPSG:32631");
  const CrsTransform geo_from_utm("EPSG:32631", kWgs84Geographic3D);
  // Central meridian of zone 31 at the equator: (500000, 0).
  EXPECT_LT((utm_from_geo.Apply({3, 0, 12.5}) - Eigen::Vector3d(500000, 0, 12.5)).norm(), 1e-6);
  for (const Eigen::Vector3d& g : {Eigen::Vector3d(5.44, 43.26, 250.0), Eigen::Vector3d(2.1, 48.8, -30.0)}) {
    const Eigen::Vector3d u = utm_from_geo.Apply(g);
    EXPECT_DOUBLE_EQ(u.z(), g.z());  // 2D projected CRS: height passes through
    const Eigen::Vector3d back = geo_from_utm.Apply(u);
    EXPECT_LT((back.head<2>() - g.head<2>()).norm(), 1e-9);
    EXPECT_DOUBLE_EQ(back.z(), g.z());
  }
  const Eigen::Vector3d marseille = utm_from_geo.Apply({5.44, 43.26, 0});
  EXPECT_NEAR(marseille.x(), 697000, 2000);  // east of the zone's central meridian
  EXPECT_NEAR(marseille.y(), 4792000, 3000);
}

TEST(CrsTransform, BatchApplyMatchesSingle) {
  const CrsTransform t(kWgs84Geographic3D, "EPSG:32631");
  std::vector<Eigen::Vector3d> points = {{5.4, 43.2, 1}, {5.5, 43.3, 2}};
  const std::vector<Eigen::Vector3d> in = points;
  t.Apply(&points);
  for (size_t i = 0; i < in.size(); ++i) EXPECT_EQ(points[i], t.Apply(in[i]));
}

TEST(CrsTransform, UnknownCrsIsNamed) {
  try {
    CrsTransform("EPSG:999999", kWgs84Geographic3D);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find("EPSG:999999"), std::string::npos);
  }
}

TEST(Crs, WktAndGeographic) {
  EXPECT_TRUE(CrsIsGeographic(kWgs84Geographic3D));
  EXPECT_FALSE(CrsIsGeographic("EPSG:32631"));
  EXPECT_NE(CrsToWkt("EPSG:32631").find("UTM zone 31N"), std::string::npos);
  EXPECT_THROW(CrsToWkt("not a crs"), Error);
}

}  // namespace
}  // namespace satmesh
