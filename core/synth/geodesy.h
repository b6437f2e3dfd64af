#pragma once
// WGS84 geodetic <-> ECEF conversions (double). Used by the exact pushbroom cameras,
// where per-pixel calls make a PROJ round trip too slow.
#include <Eigen/Core>

namespace satmesh::synth {

inline constexpr double kWgs84A = 6378137.0;                  // semi-major axis, m
inline constexpr double kWgs84F = 1.0 / 298.257223563;        // flattening
inline constexpr double kWgs84E2 = kWgs84F * (2.0 - kWgs84F);  // first eccentricity squared
inline constexpr double kEarthGm = 3.986004418e14;            // m^3/s^2

// (lon deg, lat deg, h m ellipsoidal) -> ECEF metres.
Eigen::Vector3d EcefFromGeo(const Eigen::Vector3d& lon_lat_h);
// ECEF metres -> (lon deg, lat deg, h m); exact to < 1e-9 m for |h| < 1000 km.
Eigen::Vector3d GeoFromEcef(const Eigen::Vector3d& ecef);
// Unit ellipsoid normal (local "up") at (lon, lat) in ECEF; also d(h)/d(ecef).
Eigen::Vector3d UpAt(double lon_deg, double lat_deg);
// Local east and north unit vectors at (lon, lat) in ECEF.
Eigen::Vector3d EastAt(double lon_deg, double lat_deg);
Eigen::Vector3d NorthAt(double lon_deg, double lat_deg);

}  // namespace satmesh::synth
