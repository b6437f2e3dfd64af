#include "core/synth/geodesy.h"

#include <cmath>

namespace satmesh::synth {
namespace {
constexpr double kDeg = M_PI / 180.0;
}  // namespace

Eigen::Vector3d EcefFromGeo(const Eigen::Vector3d& lon_lat_h) {
  const double lon = lon_lat_h.x() * kDeg, lat = lon_lat_h.y() * kDeg, h = lon_lat_h.z();
  const double s = std::sin(lat), c = std::cos(lat);
  const double n = kWgs84A / std::sqrt(1.0 - kWgs84E2 * s * s);
  return {(n + h) * c * std::cos(lon), (n + h) * c * std::sin(lon),
          (n * (1.0 - kWgs84E2) + h) * s};
}

Eigen::Vector3d GeoFromEcef(const Eigen::Vector3d& ecef) {
  const double p = std::hypot(ecef.x(), ecef.y());
  const double lon = std::atan2(ecef.y(), ecef.x());
  double lat = std::atan2(ecef.z(), p * (1.0 - kWgs84E2));
  double h = 0;
  for (int it = 0; it < 8; ++it) {  // fixed point; converges to 1e-15 rad in ~4 rounds
    const double s = std::sin(lat);
    const double n = kWgs84A / std::sqrt(1.0 - kWgs84E2 * s * s);
    h = p / std::cos(lat) - n;
    lat = std::atan2(ecef.z(), p * (1.0 - kWgs84E2 * n / (n + h)));
  }
  const double s = std::sin(lat);
  const double n = kWgs84A / std::sqrt(1.0 - kWgs84E2 * s * s);
  h = p * std::cos(lat) + ecef.z() * s - kWgs84A * kWgs84A / n;
  return {lon / kDeg, lat / kDeg, h};
}

Eigen::Vector3d UpAt(double lon_deg, double lat_deg) {
  const double lon = lon_deg * kDeg, lat = lat_deg * kDeg;
  return {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

Eigen::Vector3d EastAt(double lon_deg, double lat_deg) {
  const double lon = lon_deg * kDeg;
  return {-std::sin(lon), std::cos(lon), 0.0};
}

Eigen::Vector3d NorthAt(double lon_deg, double lat_deg) {
  const double lon = lon_deg * kDeg, lat = lat_deg * kDeg;
  return {-std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat)};
}

}  // namespace satmesh::synth
