#include "core/geo/local_frame.h"

#include <cmath>
#include <numbers>

namespace satmesh {
namespace {
constexpr double kWgs84A = 6378137.0;                  // semi-major axis, m
constexpr double kWgs84F = 1.0 / 298.257223563;        // flattening
constexpr double kWgs84E2 = kWgs84F * (2.0 - kWgs84F);  // first eccentricity squared
}  // namespace

LocalFrame::LocalFrame(const Eigen::Vector3d& center_lon_lat_h) : center_(center_lon_lat_h) {
  const double lat = center_lon_lat_h.y() * std::numbers::pi / 180.0;
  const double s = std::sin(lat);
  const double w = 1.0 - kWgs84E2 * s * s;
  const double n = kWgs84A / std::sqrt(w);                   // prime vertical radius
  const double m = kWgs84A * (1.0 - kWgs84E2) / (w * std::sqrt(w));  // meridian radius
  m_per_deg_lat_ = m * std::numbers::pi / 180.0;
  m_per_deg_lon_ = n * std::cos(lat) * std::numbers::pi / 180.0;
}

Eigen::Vector3d LocalFrame::LocalFromGeo(const Eigen::Vector3d& lon_lat_h) const {
  return {(lon_lat_h.x() - center_.x()) * m_per_deg_lon_,
          (lon_lat_h.y() - center_.y()) * m_per_deg_lat_, lon_lat_h.z() - center_.z()};
}

Eigen::Vector3d LocalFrame::GeoFromLocal(const Eigen::Vector3d& xyz) const {
  return {center_.x() + xyz.x() / m_per_deg_lon_, center_.y() + xyz.y() / m_per_deg_lat_,
          center_.z() + xyz.z()};
}

Eigen::Vector3d LocalFrame::GeoFromLocalScale() const {
  return {1.0 / m_per_deg_lon_, 1.0 / m_per_deg_lat_, 1.0};
}

}  // namespace satmesh
