#pragma once
// An exact pushbroom line scanner on a circular orbit (WGS84 ECEF, Earth rotation
// ignored). Row y is imaged at time t = (y - row_center) * line_period_s from the orbit
// position p(t); the detector line spans the columns in the scan plane of the body frame
// at t. Pixel coordinates follow GDAL (pixel (i, j) centre at (i+0.5, j+0.5)).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

namespace satmesh::synth {

struct PushbroomParams {
  Eigen::Vector3d orbit_u{1, 0, 0};  // ECEF unit vector: position direction at t = 0
  Eigen::Vector3d orbit_v{0, 1, 0};  // ECEF unit vector: velocity direction at t = 0
  double orbit_radius_m = 6978137;   // |p(t)|
  double angular_rate_rad_s = 1e-3;  // orbital angular rate
  // Body axes (x: detector line, y: scan-plane normal, z: boresight) in the orbit frame
  // [along-track, nadir x along-track, nadir]; constant, so attitude follows the orbit.
  Eigen::Matrix3d orbit_from_body = Eigen::Matrix3d::Identity();
  double focal_px = 1e6;        // focal length in pixels
  double col_center = 0;        // column of the boresight
  double row_center = 0;        // row imaged at t = 0
  double line_period_s = 4e-5;  // time per row
  int width = 0, height = 0;    // image size, pixels
};

struct ViewGeometrySetup {
  Eigen::Vector3d center_lon_lat_h{0, 0, 0};  // scene centre (imaged at t = 0)
  double off_nadir_deg = 20;   // angle at the satellite between nadir and the centre, [0, 45]
  double azimuth_deg = 0;      // azimuth of the satellite seen from the centre, clockwise from N
  double altitude_m = 600e3;   // orbit altitude above the centre's ellipsoid radius, > 0
  double track_heading_deg = 190;  // ground-track heading at t = 0, clockwise from N
  double gsd_m = 0.3;          // pixel size perpendicular to the line of sight, > 0
  int margin_px = 16;          // image margin around the footprint of `cover`, >= 0
  std::string Check() const;
};

class PushbroomCamera {
 public:
  PushbroomCamera() = default;
  explicit PushbroomCamera(const PushbroomParams& params) : p_(params) {}
  // Builds the camera looking at setup.center at t = 0, sized so that every point of
  // `cover_lon_lat_h` projects at least margin_px inside the image.
  static PushbroomCamera LookingAt(const ViewGeometrySetup& setup,
                                   const std::vector<Eigen::Vector3d>& cover_lon_lat_h);

  const PushbroomParams& params() const { return p_; }
  int width() const { return p_.width; }
  int height() const { return p_.height; }

  Eigen::Vector3d PositionAt(double t) const;        // ECEF orbit position
  Eigen::Matrix3d EcefFromBodyAt(double t) const;    // columns: body x, y, z in ECEF
  double TimeOfRow(double row) const { return (row - p_.row_center) * p_.line_period_s; }

  // Exact projection (Newton on the scan-plane condition). nullopt behind the sensor or
  // if the iteration fails.
  std::optional<Eigen::Vector2d> PixelFromEcef(const Eigen::Vector3d& ecef) const;
  std::optional<Eigen::Vector2d> PixelFromGeo(const Eigen::Vector3d& lon_lat_h) const;
  // Line of sight of (col, row): ECEF origin (the orbit position) and unit direction.
  void RayForPixel(const Eigen::Vector2d& col_row, Eigen::Vector3d* origin_ecef,
                   Eigen::Vector3d* direction_ecef) const;
  // (lon, lat, h) where the line of sight of (col, row) reaches ellipsoidal height h.
  std::optional<Eigen::Vector3d> LocalizeAtHeight(const Eigen::Vector2d& col_row,
                                                  double h) const;

  // Off-nadir angle (deg) at the satellite and azimuth/zenith (deg) of the satellite
  // seen from a ground point, for the line of sight through that point.
  double OffNadirDeg(const Eigen::Vector3d& lon_lat_h) const;
  Eigen::Vector2d SatelliteAzimuthZenithDeg(const Eigen::Vector3d& lon_lat_h) const;
  // Ground sample distance on the horizontal plane at a point: sqrt of a pixel's area.
  double GroundGsdM(const Eigen::Vector3d& lon_lat_h) const;

 private:
  PushbroomParams p_;
};

}  // namespace satmesh::synth
