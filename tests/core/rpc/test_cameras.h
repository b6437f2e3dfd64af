#pragma once
// Test-local cameras and fixtures: a pushbroom line scanner on a ~600 km circular orbit
// (off-nadir view, slowly varying attitude), realistic RPCs fitted to it, GeoTIFF writers.
#include <cpl_string.h>
#include <gdal.h>

#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

#include "core/common/gdal_init.h"
#include "core/rpc/rpc_fit.h"
#include "core/rpc/rpc_model.h"

namespace satmesh::test {

inline Eigen::Vector3d EcefFromGeo(const Eigen::Vector3d& lon_lat_h) {
  constexpr double a = 6378137.0, f = 1.0 / 298.257223563, e2 = f * (2 - f);
  const double lon = lon_lat_h.x() * std::numbers::pi / 180, lat = lon_lat_h.y() * std::numbers::pi / 180;
  const double n = a / std::sqrt(1 - e2 * std::sin(lat) * std::sin(lat));
  return {(n + lon_lat_h.z()) * std::cos(lat) * std::cos(lon),
          (n + lon_lat_h.z()) * std::cos(lat) * std::sin(lon),
          (n * (1 - e2) + lon_lat_h.z()) * std::sin(lat)};
}

struct PushbroomParams {
  Eigen::Vector3d center_lon_lat_h{5.44, 43.26, 0.0};
  double zenith_deg = 20;        // view zenith angle at the scene centre
  double azimuth_deg = 100;      // azimuth of the satellite seen from the ground
  double altitude_m = 600e3;
  double gsd_m = 0.4;
  double image_size_px = 2000;
  double attitude_amplitude_rad = 10e-6;  // sinusoidal roll/pitch/yaw
  double attitude_period_s = 2.0;
  double attitude_drift_rad_s = 20e-6;
};

// (col, row) in GDAL convention of a geodetic point, by solving for the scan time.
class PushbroomCamera {
 public:
  explicit PushbroomCamera(const PushbroomParams& p) : p_(p) {
    const double lon = p.center_lon_lat_h.x() * std::numbers::pi / 180;
    const double lat = p.center_lon_lat_h.y() * std::numbers::pi / 180;
    const Eigen::Vector3d x0 = EcefFromGeo(p.center_lon_lat_h);
    const Eigen::Vector3d up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
    const Eigen::Vector3d east(-std::sin(lon), std::cos(lon), 0);
    const Eigen::Vector3d north = up.cross(east);
    const double z = p.zenith_deg * std::numbers::pi / 180, az = p.azimuth_deg * std::numbers::pi / 180;
    const Eigen::Vector3d w = std::cos(z) * up + std::sin(z) * (std::sin(az) * east + std::cos(az) * north);
    radius_ = 6371e3 + p.altitude_m;
    const double b = x0.dot(w);
    const double rho = -b + std::sqrt(b * b - x0.squaredNorm() + radius_ * radius_);
    const Eigen::Vector3d s0 = x0 + rho * w;
    r0_ = s0.normalized();
    v0_ = (Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ().dot(r0_) * r0_).normalized();
    c_ = r0_.cross(v0_);
    omega_ = std::sqrt(3.986004418e14 / (radius_ * radius_ * radius_));
    const Eigen::Vector3d d0 = -w;  // boresight, satellite -> scene centre
    boresight_orb_ = {d0.dot(r0_), d0.dot(v0_), d0.dot(c_)};
    Eigen::Vector3d x_axis = c_ - c_.dot(d0) * d0;
    x_axis.normalize();
    xaxis_orb_ = {x_axis.dot(r0_), x_axis.dot(v0_), x_axis.dot(c_)};
    focal_px_ = rho / p.gsd_m;
    line_period_s_ = p.gsd_m / (omega_ * x0.norm());
  }

  Eigen::Vector2d operator()(const Eigen::Vector3d& lon_lat_h) const {
    const Eigen::Vector3d x = EcefFromGeo(lon_lat_h);
    double t = 0, f = ScanPlaneOffset(x, t);
    double t1 = 1e-3, f1 = ScanPlaneOffset(x, t1);
    for (int i = 0; i < 30 && std::abs(t1 - t) > 1e-13 && f1 != f; ++i) {  // secant on time
      const double t2 = t1 - f1 * (t1 - t) / (f1 - f);
      t = t1, f = f1, t1 = t2, f1 = ScanPlaneOffset(x, t1);
    }
    Eigen::Matrix3d axes = Axes(t1);
    const Eigen::Vector3d q = axes.transpose() * (x - Satellite(t1));
    return {0.5 * p_.image_size_px + focal_px_ * q.x() / q.z(),
            0.5 * p_.image_size_px + t1 / line_period_s_};
  }

  // A lon/lat/h box around the centre covering about the image.
  void Box(Eigen::Vector3d* lo, Eigen::Vector3d* hi, double h_min = 0, double h_max = 100) const {
    const double half_m = 0.5 * p_.image_size_px * p_.gsd_m;
    const double lat = p_.center_lon_lat_h.y() * std::numbers::pi / 180;
    const Eigen::Vector3d half(half_m / (111320.0 * std::cos(lat)), half_m / 111130.0, 0);
    *lo = p_.center_lon_lat_h - half, *hi = p_.center_lon_lat_h + half;
    lo->z() = h_min, hi->z() = h_max;
  }

 private:
  Eigen::Vector3d Satellite(double t) const {
    return radius_ * (std::cos(omega_ * t) * r0_ + std::sin(omega_ * t) * v0_);
  }
  // Columns: camera x (along the scan line), y (along track), z (boresight), in ECEF.
  Eigen::Matrix3d Axes(double t) const {
    const double ph = 2 * std::numbers::pi * t / p_.attitude_period_s;
    const double a = p_.attitude_amplitude_rad, d = p_.attitude_drift_rad_s * t;
    const Eigen::Matrix3d pert =
        (Eigen::AngleAxisd(a * std::sin(ph) + d, Eigen::Vector3d::UnitX()) *
         Eigen::AngleAxisd(a * std::sin(ph + 1.0) - d, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(a * std::sin(ph + 2.0), Eigen::Vector3d::UnitZ())).toRotationMatrix();
    Eigen::Matrix3d orb;
    orb.col(0) = std::cos(omega_ * t) * r0_ + std::sin(omega_ * t) * v0_;
    orb.col(1) = -std::sin(omega_ * t) * r0_ + std::cos(omega_ * t) * v0_;
    orb.col(2) = c_;
    const Eigen::Vector3d zc = orb * pert * boresight_orb_, xc = orb * pert * xaxis_orb_;
    Eigen::Matrix3d axes;
    axes << xc, zc.cross(xc), zc;
    return axes;
  }
  double ScanPlaneOffset(const Eigen::Vector3d& x, double t) const {
    const Eigen::Matrix3d axes = Axes(t);
    const Eigen::Vector3d p = x - Satellite(t);
    return axes.col(1).dot(p) / axes.col(2).dot(p);
  }

  PushbroomParams p_;
  double radius_ = 0, omega_ = 0, focal_px_ = 0, line_period_s_ = 0;
  Eigen::Vector3d r0_, v0_, c_, boresight_orb_, xaxis_orb_;
};

// A WorldView/Pléiades-like RPC: FitRpc on a pushbroom camera.
inline RpcFitResult FitPushbroom(const PushbroomParams& params, const RpcFitOptions& options = {}) {
  const PushbroomCamera camera(params);
  Eigen::Vector3d lo, hi;
  camera.Box(&lo, &hi);
  return FitRpc([&camera](const Eigen::Vector3d& g) { return camera(g); }, lo, hi, options);
}

// Writes a tiny GeoTIFF carrying `rpc_metadata` in the "RPC" domain.
inline void WriteRpcGeoTiff(const std::string& path, const std::map<std::string, std::string>& rpc_metadata,
                            const char* const* creation_options = nullptr) {
  EnsureGdalInitialized();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  GDALDatasetH ds = GDALCreate(driver, path.c_str(), 8, 8, 1, GDT_Byte,
                               const_cast<char**>(creation_options));
  char** md = nullptr;
  for (const auto& [k, v] : rpc_metadata) md = CSLSetNameValue(md, k.c_str(), v.c_str());
  GDALSetMetadata(ds, md, "RPC");
  CSLDestroy(md);
  GDALClose(ds);
}

}  // namespace satmesh::test
