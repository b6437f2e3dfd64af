#pragma once
// The quasi-Cartesian tile frame of the paper (3.2.2):
//   x = (lon - lon_c) * m_per_deg_lon, y = (lat - lat_c) * m_per_deg_lat, z = h - h_c
// with the metres-per-degree scales from the WGS84 radii of curvature at the centre.
// Exactly invertible, so the RFM is always evaluated on exact geodetic coordinates.
#include <Eigen/Core>

namespace satmesh {

class LocalFrame {
 public:
  LocalFrame() = default;
  // Frame centred at (lon_c, lat_c, h_c) (degrees, degrees, metres ellipsoidal).
  explicit LocalFrame(const Eigen::Vector3d& center_lon_lat_h);

  Eigen::Vector3d LocalFromGeo(const Eigen::Vector3d& lon_lat_h) const;
  Eigen::Vector3d GeoFromLocal(const Eigen::Vector3d& xyz) const;
  // d(lon,lat,h)/d(x,y,z): diagonal (1/m_per_deg_lon, 1/m_per_deg_lat, 1).
  Eigen::Vector3d GeoFromLocalScale() const;

  const Eigen::Vector3d& center_lon_lat_h() const { return center_; }
  double meters_per_degree_lon() const { return m_per_deg_lon_; }
  double meters_per_degree_lat() const { return m_per_deg_lat_; }

 private:
  Eigen::Vector3d center_{0, 0, 0};
  double m_per_deg_lon_ = 1, m_per_deg_lat_ = 1;
};

}  // namespace satmesh
