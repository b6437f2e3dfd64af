#include "core/geo/local_frame.h"

#include <geodesic.h>
#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/geo/crs.h"

namespace satmesh {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

TEST(LocalFrame, ExactInverseRoundTrip) {
  const LocalFrame frame({5.44, 43.26, 120});
  for (double x = -5000; x <= 5000; x += 1250)
    for (double y = -5000; y <= 5000; y += 1250) {
      const Eigen::Vector3d geo = frame.GeoFromLocal({x, y, 37.5});
      EXPECT_LT((frame.LocalFromGeo(geo) - Eigen::Vector3d(x, y, 37.5)).norm(), 1e-9);
      const Eigen::Vector3d g(5.44 + x * 1e-5, 43.26 + y * 1e-5, 50);
      EXPECT_LT((frame.GeoFromLocal(frame.LocalFromGeo(g)) - g).norm(), 1e-9);
    }
  EXPECT_EQ(frame.LocalFromGeo({5.44, 43.26, 120}), Eigen::Vector3d::Zero());
}

TEST(LocalFrame, ScalesFromWgs84RadiiOfCurvature) {
  // At the equator: M = a(1-e^2), N = a. At 43.26 N (Marseille) against the classic
  // series for the length of a degree on WGS84 (111132.954 - 559.822 cos 2φ + ...).
  const LocalFrame equator({0, 0, 0});
  EXPECT_NEAR(equator.meters_per_degree_lon(), 6378137.0 * kDeg, 1e-6);
  EXPECT_NEAR(equator.meters_per_degree_lat(), 6335439.327 * kDeg, 1e-3);
  const LocalFrame marseille({5.44, 43.26, 0});
  const double phi = 43.26 * kDeg;
  EXPECT_NEAR(marseille.meters_per_degree_lat(),
              111132.954 - 559.822 * std::cos(2 * phi) + 1.175 * std::cos(4 * phi), 0.05);
  EXPECT_NEAR(marseille.meters_per_degree_lon(),
              111412.84 * std::cos(phi) - 93.5 * std::cos(3 * phi) + 0.118 * std::cos(5 * phi), 0.05);
  const Eigen::Vector3d s = marseille.GeoFromLocalScale();
  EXPECT_DOUBLE_EQ(s.x() * marseille.meters_per_degree_lon(), 1.0);
  EXPECT_DOUBLE_EQ(s.y() * marseille.meters_per_degree_lat(), 1.0);
  EXPECT_EQ(s.z(), 1.0);
}

// Paper Table 1: distortion of the local frame at 100 m ... 5000 m from the centre,
// measured against geodesics on the WGS84 ellipsoid (PROJ's geodesic routines): the
// distance error and the error of the direction (azimuth); orthogonality: the angle
// between the frame images of two perpendicular geodesics.
TEST(LocalFrame, DistortionTableAgainstGeodesics) {
  geod_geodesic g;
  geod_init(&g, 6378137.0, 1 / 298.257223563);
  const Eigen::Vector3d center(5.44, 43.26, 0);
  const LocalFrame frame(center);
  std::printf("distance_m  max_dist_err_m  max_azimuth_err_deg  max_orthogonality_err_deg\n");
  for (double d : {100.0, 500.0, 1000.0, 2000.0, 5000.0}) {
    double dist_err = 0, az_err = 0, ortho_err = 0;
    for (double az = 0; az < 360; az += 15) {
      auto local = [&](double azimuth) {
        double lat2, lon2;
        geod_direct(&g, center.y(), center.x(), azimuth, d, &lat2, &lon2, nullptr);
        return frame.LocalFromGeo({lon2, lat2, 0}).head<2>().eval();
      };
      const Eigen::Vector2d p = local(az), q = local(az + 90);
      dist_err = std::max(dist_err, std::abs(p.norm() - d));
      double da = std::atan2(p.x(), p.y()) / kDeg - az;
      da = std::remainder(da, 360.0);
      az_err = std::max(az_err, std::abs(da));
      const double angle = std::acos(p.normalized().dot(q.normalized())) / kDeg;
      ortho_err = std::max(ortho_err, std::abs(angle - 90));
    }
    std::printf("%10.0f  %14.4f  %19.6f  %25.6f\n", d, dist_err, az_err, ortho_err);
    // Second-order distortion ~ d^2 tan(lat) / (2R): 3 cm at 1 km, 0.8 m at 5 km.
    if (d <= 1000) {
      EXPECT_LT(dist_err, 0.04) << "the paper's < 4 cm over a 2 km tile";
    }
    EXPECT_LT(dist_err, 1.0 * (d / 5000) * (d / 5000));
    EXPECT_LT(az_err, 0.01 * d / 1000);
    EXPECT_LT(ortho_err, 0.01 * d / 1000);
  }
}

// The frame against UTM (EPSG:32631) corrected by the UTM point scale factor at the
// centre and rotated by its grid convergence. The difference is dominated by the frame's
// own second-order shear (azimuth error ~0.0046 deg at 1 km, i.e. ~8 cm sideways).
TEST(LocalFrame, AgreesWithScaledUtm) {
  const Eigen::Vector3d center(5.44, 43.26, 0);
  const LocalFrame frame(center);
  const CrsTransform utm_from_geo(kWgs84Geographic3D, "EPSG:32631");
  const Eigen::Vector3d c_utm = utm_from_geo.Apply(center);
  // Scale factor and grid convergence at the centre from a tiny local displacement.
  const Eigen::Vector3d e_utm = utm_from_geo.Apply(frame.GeoFromLocal({10, 0, 0})) - c_utm;
  const double k = e_utm.head<2>().norm() / 10, gamma = std::atan2(e_utm.y(), e_utm.x());
  const Eigen::Rotation2Dd rot(-gamma);
  for (double d : {100.0, 1000.0, 2000.0}) {
    double worst = 0;
    for (double az = 0; az < 360; az += 30) {
      const Eigen::Vector3d xyz(d * std::sin(az * kDeg), d * std::cos(az * kDeg), 0);
      const Eigen::Vector3d u = utm_from_geo.Apply(frame.GeoFromLocal(xyz)) - c_utm;
      const Eigen::Vector2d utm_local = rot * u.head<2>() / k;
      worst = std::max(worst, (utm_local - xyz.head<2>()).norm());
    }
    std::printf("vs UTM at %5.0f m: max position difference %.4f m\n", d, worst);
    EXPECT_LT(worst, 0.1 * (d / 1000) * (d / 1000) + 0.002);
  }
}

}  // namespace
}  // namespace satmesh
