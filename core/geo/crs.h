#pragma once
// Point transforms between coordinate reference systems through GDAL/PROJ.
// CRS strings: "EPSG:32631", WKT, PROJ strings — anything OGRSpatialReference::SetFromUserInput
// takes. Geographic CRSs use (lon, lat) axis order (traditional GIS order) everywhere.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

namespace satmesh {

inline constexpr const char* kWgs84Geographic3D = "EPSG:4979";  // lon, lat, ellipsoidal h

// Throws Error{kInvalidInput} naming the CRS if it cannot be parsed.
std::string CrsToWkt(const std::string& crs);
bool CrsIsGeographic(const std::string& crs);
bool CrsIsProjected(const std::string& crs);  // metres on a map (not geographic, not ECEF)
// The WGS84 UTM zone's CRS at a point ("EPSG:326zz" north, "EPSG:327zz" south).
std::string UtmCrsAt(double lon_deg, double lat_deg);

class CrsTransform {
 public:
  // Throws Error{kInvalidInput} if either CRS is unknown or no transform exists.
  CrsTransform(const std::string& source_crs, const std::string& target_crs);
  ~CrsTransform();
  CrsTransform(CrsTransform&&) noexcept;
  CrsTransform& operator=(CrsTransform&&) noexcept;

  Eigen::Vector3d Apply(const Eigen::Vector3d& point) const;
  // In place; throws Error{kInvalidInput} if any point fails to transform.
  void Apply(std::vector<Eigen::Vector3d>* points) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace satmesh
