#include "core/synth/pushbroom_camera.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/common/error.h"
#include "core/synth/geodesy.h"

namespace satmesh::synth {
namespace {
constexpr double kDeg = M_PI / 180.0;
}  // namespace

std::string ViewGeometrySetup::Check() const {
  if (!(off_nadir_deg >= 0 && off_nadir_deg <= 45)) return "off_nadir_deg must be in [0, 45]";
  if (!(altitude_m > 0)) return "altitude_m must be > 0";
  if (!(gsd_m > 0)) return "gsd_m must be > 0";
  if (margin_px < 0) return "margin_px must be >= 0";
  return "";
}

Eigen::Vector3d PushbroomCamera::PositionAt(double t) const {
  const double a = p_.angular_rate_rad_s * t;
  return p_.orbit_radius_m * (std::cos(a) * p_.orbit_u + std::sin(a) * p_.orbit_v);
}

Eigen::Matrix3d PushbroomCamera::EcefFromBodyAt(double t) const {
  const double a = p_.angular_rate_rad_s * t;
  const Eigen::Vector3d along = -std::sin(a) * p_.orbit_u + std::cos(a) * p_.orbit_v;
  const Eigen::Vector3d nadir = -(std::cos(a) * p_.orbit_u + std::sin(a) * p_.orbit_v);
  Eigen::Matrix3d ecef_from_orbit;
  ecef_from_orbit << along, nadir.cross(along), nadir;
  return ecef_from_orbit * p_.orbit_from_body;
}

std::optional<Eigen::Vector2d> PushbroomCamera::PixelFromEcef(const Eigen::Vector3d& x) const {
  auto scan = [&](double t) { return EcefFromBodyAt(t).col(1).dot(x - PositionAt(t)); };
  double t = 0;
  bool converged = false;
  for (int it = 0; it < 30; ++it) {
    const double h = 1e-3;
    const double g = scan(t), dg = (scan(t + h) - scan(t - h)) / (2 * h);
    if (!(std::abs(dg) > 0)) return std::nullopt;
    const double step = g / dg;
    t -= step;
    if (!std::isfinite(t)) return std::nullopt;
    if (std::abs(step) < 1e-6 * p_.line_period_s) {
      converged = true;
      break;
    }
  }
  if (!converged) return std::nullopt;
  const Eigen::Matrix3d body = EcefFromBodyAt(t);
  const Eigen::Vector3d rel = x - PositionAt(t);
  const double z = body.col(2).dot(rel);
  if (!(z > 0)) return std::nullopt;
  return Eigen::Vector2d(p_.col_center + p_.focal_px * body.col(0).dot(rel) / z,
                         p_.row_center + t / p_.line_period_s);
}

std::optional<Eigen::Vector2d> PushbroomCamera::PixelFromGeo(
    const Eigen::Vector3d& lon_lat_h) const {
  return PixelFromEcef(EcefFromGeo(lon_lat_h));
}

void PushbroomCamera::RayForPixel(const Eigen::Vector2d& col_row, Eigen::Vector3d* origin,
                                  Eigen::Vector3d* direction) const {
  const double t = TimeOfRow(col_row.y());
  const Eigen::Matrix3d body = EcefFromBodyAt(t);
  *origin = PositionAt(t);
  *direction =
      (body.col(2) + ((col_row.x() - p_.col_center) / p_.focal_px) * body.col(0)).normalized();
}

std::optional<Eigen::Vector3d> PushbroomCamera::LocalizeAtHeight(const Eigen::Vector2d& col_row,
                                                                 double h) const {
  Eigen::Vector3d o, d;
  RayForPixel(col_row, &o, &d);
  double s = 0;
  for (int it = 0; it < 20; ++it) {
    const Eigen::Vector3d g = GeoFromEcef(o + s * d);
    const double slope = d.dot(UpAt(g.x(), g.y()));
    if (!(slope < 0)) return std::nullopt;  // not descending towards the Earth
    const double f = g.z() - h;
    s -= f / slope;
    if (std::abs(f) < 1e-6) return GeoFromEcef(o + s * d);  // ECEF ulp is ~1e-9 m
  }
  return std::nullopt;
}

double PushbroomCamera::OffNadirDeg(const Eigen::Vector3d& lon_lat_h) const {
  const Eigen::Vector3d x = EcefFromGeo(lon_lat_h);
  auto px = PixelFromEcef(x);
  if (!px) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector3d p = PositionAt(TimeOfRow(px->y()));
  return std::acos(std::clamp((-p).normalized().dot((x - p).normalized()), -1.0, 1.0)) / kDeg;
}

Eigen::Vector2d PushbroomCamera::SatelliteAzimuthZenithDeg(
    const Eigen::Vector3d& lon_lat_h) const {
  const Eigen::Vector3d x = EcefFromGeo(lon_lat_h);
  auto px = PixelFromEcef(x);
  if (!px) return {NAN, NAN};
  const Eigen::Vector3d dir = (PositionAt(TimeOfRow(px->y())) - x).normalized();
  const double lon = lon_lat_h.x(), lat = lon_lat_h.y();
  double az = std::atan2(dir.dot(EastAt(lon, lat)), dir.dot(NorthAt(lon, lat))) / kDeg;
  if (az < 0) az += 360;
  return {az, std::acos(std::clamp(dir.dot(UpAt(lon, lat)), -1.0, 1.0)) / kDeg};
}

double PushbroomCamera::GroundGsdM(const Eigen::Vector3d& lon_lat_h) const {
  const Eigen::Vector3d x = EcefFromGeo(lon_lat_h);
  const double lon = lon_lat_h.x(), lat = lon_lat_h.y();
  auto p0 = PixelFromEcef(x), pe = PixelFromEcef(x + EastAt(lon, lat)),
       pn = PixelFromEcef(x + NorthAt(lon, lat));
  if (!p0 || !pe || !pn) return std::numeric_limits<double>::quiet_NaN();
  Eigen::Matrix2d j;
  j << *pe - *p0, *pn - *p0;
  return 1.0 / std::sqrt(std::abs(j.determinant()));
}

PushbroomCamera PushbroomCamera::LookingAt(const ViewGeometrySetup& setup,
                                           const std::vector<Eigen::Vector3d>& cover) {
  const std::string why = setup.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "ViewGeometrySetup: " + why);
  const Eigen::Vector3d& c = setup.center_lon_lat_h;
  const Eigen::Vector3d xc = EcefFromGeo(c);
  const double rc = xc.norm(), r = rc + setup.altitude_m;
  // Satellite direction from the centre: zenith angle from the off-nadir angle (sine rule).
  const double zen = std::asin(std::min(1.0, r / rc * std::sin(setup.off_nadir_deg * kDeg)));
  const double az = setup.azimuth_deg * kDeg;
  const Eigen::Vector3d sdir =
      std::cos(zen) * UpAt(c.x(), c.y()) +
      std::sin(zen) * (std::sin(az) * EastAt(c.x(), c.y()) + std::cos(az) * NorthAt(c.x(), c.y()));
  const double b = xc.dot(sdir);
  const double dist = -b + std::sqrt(b * b - rc * rc + r * r);
  const Eigen::Vector3d sat = xc + dist * sdir;

  PushbroomParams p;
  p.orbit_u = sat.normalized();
  p.orbit_radius_m = sat.norm();
  p.angular_rate_rad_s = std::sqrt(kEarthGm / std::pow(p.orbit_radius_m, 3));
  const Eigen::Vector3d z_axis(0, 0, 1);
  const Eigen::Vector3d north = (z_axis - z_axis.dot(p.orbit_u) * p.orbit_u).normalized();
  const Eigen::Vector3d east = north.cross(p.orbit_u).normalized();
  const double heading = setup.track_heading_deg * kDeg;
  p.orbit_v = (std::cos(heading) * north + std::sin(heading) * east).normalized();
  // Body frame at t = 0: boresight on the centre, scan-plane normal closest to along-track.
  const Eigen::Vector3d zb = (xc - sat).normalized();
  const Eigen::Vector3d yb = (p.orbit_v - p.orbit_v.dot(zb) * zb).normalized();
  const Eigen::Vector3d xb = yb.cross(zb);
  Eigen::Matrix3d body, orbit;
  body << xb, yb, zb;
  const Eigen::Vector3d nadir = -p.orbit_u;
  orbit << p.orbit_v, nadir.cross(p.orbit_v), nadir;
  p.orbit_from_body = orbit.transpose() * body;
  p.focal_px = dist / setup.gsd_m;
  p.line_period_s = 1.0;
  // Line period: one row per gsd of motion perpendicular to the line of sight.
  auto t1 = PushbroomCamera(p).PixelFromEcef(xc + yb);
  SATMESH_CHECK(t1.has_value(), ErrorCode::kInternal, "pushbroom setup: projection failed");
  p.line_period_s = std::abs(t1->y()) * setup.gsd_m;
  // Size the image around the footprint.
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  const PushbroomCamera probe(p);
  for (const auto& g : cover) {
    auto px = probe.PixelFromGeo(g);
    SATMESH_CHECK(px.has_value(), ErrorCode::kInvalidArgument,
                  "pushbroom setup: a cover point is not visible");
    lo = lo.cwiseMin(*px);
    hi = hi.cwiseMax(*px);
  }
  if (cover.empty()) lo = hi = Eigen::Vector2d::Zero();
  p.col_center = std::ceil(-lo.x()) + setup.margin_px;
  p.row_center = std::ceil(-lo.y()) + setup.margin_px;
  p.width = int(std::ceil(hi.x() + p.col_center)) + setup.margin_px;
  p.height = int(std::ceil(hi.y() + p.row_center)) + setup.margin_px;
  return PushbroomCamera(p);
}

}  // namespace satmesh::synth
