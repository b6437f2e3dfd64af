#include "core/synth/view_plan.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "core/common/error.h"
#include "core/image/acquisition_info.h"

namespace satmesh::synth {
namespace {
constexpr double kDeg = M_PI / 180.0;
constexpr double kEarthR = 6371e3, kAltitude = 600e3;
constexpr double kGroundTrackSpeed = 7.0e3;  // m/s of a 600 km orbit's sub-satellite point

class Draw {
 public:
  explicit Draw(uint64_t seed) : gen_(seed * 0x9E3779B97F4A7C15ull + 17) {}
  double U(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(gen_); }
  int Int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(gen_); }
  double Sign() { return U(0, 1) < 0.5 ? -1 : 1; }

 private:
  std::mt19937_64 gen_;
};

// A pass of a sun-synchronous orbit: descending at 10:30 (WorldView, Pléiades) or
// ascending at 13:30 local solar time, heading as the ground track runs at mid latitudes.
struct Pass {
  double heading_deg = 190, unix_s = 0, sun_elevation_deg = 60, sun_azimuth_deg = 135;
};

Pass DrawPass(const ViewPlanOptions& o, const Eigen::Vector2d& lon_lat, Draw* draw) {
  Pass p;
  const bool descending = draw->U(0, 1) < 0.5;
  p.heading_deg = (descending ? 190 : 350) + draw->U(-5, 5);
  const double local_h = (descending ? 10.5 : 13.5) + draw->U(-o.local_time_jitter_h, o.local_time_jitter_h);
  const int year = draw->Int(o.first_year, o.last_year);
  const long long jan1 = DaysFromCivil(year, 1, 1);
  const int days = int(DaysFromCivil(year + 1, 1, 1) - jan1);
  const int doy = draw->Int(1, days);
  const double utc_h = local_h - lon_lat.x() / 15;
  p.unix_s = double(jan1 + doy - 1) * 86400 + utc_h * 3600;
  const Eigen::Vector2d sun = SunElevationAzimuthDeg(lon_lat.y(), doy, local_h);
  p.sun_elevation_deg = sun.x(), p.sun_azimuth_deg = sun.y();
  return p;
}

PlannedView ViewOfPass(const Pass& pass, int index, double pitch_deg, double roll_deg) {
  PlannedView v;
  v.off_nadir_azimuth_deg = OffNadirAzimuthFromPitchRoll(pitch_deg, roll_deg, pass.heading_deg);
  v.track_heading_deg = pass.heading_deg;
  v.pass = index;
  v.pitch_deg = pitch_deg, v.roll_deg = roll_deg;
  // A forward look (pitch > 0) is taken before the satellite passes the scene.
  v.acquisition_unix_s = pass.unix_s - kAltitude * std::tan(pitch_deg * kDeg) / kGroundTrackSpeed;
  v.sun_elevation_deg = pass.sun_elevation_deg, v.sun_azimuth_deg = pass.sun_azimuth_deg;
  return v;
}

// Pitch offset a in [0, 45] such that angle(view(a)) = target_deg; angle(a) increases with a.
double SolveOffset(const std::function<double(double)>& angle_of_offset, double target_deg) {
  double lo = 0, hi = 45;
  SATMESH_CHECK(angle_of_offset(hi) >= target_deg, ErrorCode::kInvalidArgument,
                "view plan: convergence " + std::to_string(target_deg) + " deg out of reach along track");
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (angle_of_offset(mid) < target_deg ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

std::vector<PlannedView> PlanStereo(const ViewPlanOptions& o, const Eigen::Vector2d& lon_lat, Draw* d) {
  const Pass pass = DrawPass(o, lon_lat, d);
  const double roll = d->Sign() * d->U(0, o.stereo_max_roll_deg);
  const double p0 = d->U(-o.max_center_pitch_deg, o.max_center_pitch_deg);
  const double gamma = d->U(o.stereo_min_convergence_deg, o.stereo_max_convergence_deg);
  const double h = pass.heading_deg;
  const double a = SolveOffset(
      [&](double x) {
        return ViewIntersectionAngleDeg(OffNadirAzimuthFromPitchRoll(p0 + x, roll, h),
                                        OffNadirAzimuthFromPitchRoll(p0 - x, roll, h));
      },
      gamma);
  return {ViewOfPass(pass, 0, p0 + a, roll), ViewOfPass(pass, 0, p0 - a, roll)};
}

std::vector<PlannedView> PlanTriStereo(const ViewPlanOptions& o, const Eigen::Vector2d& lon_lat, Draw* d) {
  const Pass pass = DrawPass(o, lon_lat, d);
  const double roll = d->Sign() * d->U(0, o.tristereo_max_roll_deg);
  const double pm = d->U(-o.max_center_pitch_deg, o.max_center_pitch_deg);
  const double h = pass.heading_deg;
  const Eigen::Vector2d mid = OffNadirAzimuthFromPitchRoll(pm, roll, h);
  double pitch[2];
  for (int k = 0; k < 2; ++k) {  // fore (+), aft (-)
    const double s = k == 0 ? 1 : -1;
    const double gamma = d->U(o.tristereo_min_convergence_deg, o.tristereo_max_convergence_deg);
    pitch[k] = pm + s * SolveOffset(
        [&](double x) { return ViewIntersectionAngleDeg(OffNadirAzimuthFromPitchRoll(pm + s * x, roll, h), mid); },
        gamma);
  }
  return {ViewOfPass(pass, 0, pitch[0], roll), ViewOfPass(pass, 0, pm, roll), ViewOfPass(pass, 0, pitch[1], roll)};
}

std::vector<PlannedView> PlanMultiDate(const ViewPlanOptions& o, const Eigen::Vector2d& lon_lat, Draw* d) {
  std::vector<PlannedView> views;
  while (int(views.size()) < o.num_views) {
    Eigen::Vector2d dir;
    bool apart = false;
    for (int attempt = 0; attempt < 1000 && !apart; ++attempt) {
      dir = {d->U(o.min_off_nadir_deg, o.max_off_nadir_deg), d->U(0, 360)};
      apart = std::all_of(views.begin(), views.end(), [&](const PlannedView& v) {
        return ViewIntersectionAngleDeg(v.off_nadir_azimuth_deg, dir) >= o.min_separation_deg;
      });
    }
    SATMESH_CHECK(apart, ErrorCode::kInvalidArgument,
                  "view plan: no room for " + std::to_string(o.num_views) + " views " +
                      std::to_string(o.min_separation_deg) + " deg apart");
    const Pass pass = DrawPass(o, lon_lat, d);
    PlannedView v = ViewOfPass(pass, 0, 0, 0);
    v.off_nadir_azimuth_deg = dir;
    views.push_back(v);
  }
  // An archive lists its images by date: passes numbered in time order.
  std::sort(views.begin(), views.end(),
            [](const PlannedView& a, const PlannedView& b) { return a.acquisition_unix_s < b.acquisition_unix_s; });
  for (int i = 0; i < int(views.size()); ++i) views[i].pass = i;
  return views;
}

int NumViewsOf(Acquisition a) {
  switch (a) {
    case Acquisition::kStereo: return 2;
    case Acquisition::kTriStereo: return 3;
    case Acquisition::kMultiDate: return 6;
    case Acquisition::kJax: return 26;
  }
  return 0;
}

}  // namespace

std::string AcquisitionName(Acquisition a) {
  switch (a) {
    case Acquisition::kStereo: return "stereo";
    case Acquisition::kTriStereo: return "tristereo";
    case Acquisition::kMultiDate: return "multidate";
    case Acquisition::kJax: return "jax";
  }
  return "?";
}

std::optional<Acquisition> ParseAcquisition(const std::string& name) {
  for (Acquisition a : {Acquisition::kStereo, Acquisition::kTriStereo, Acquisition::kMultiDate, Acquisition::kJax})
    if (AcquisitionName(a) == name) return a;
  return std::nullopt;
}

ViewPlanOptions ForAcquisition(Acquisition acquisition) {
  ViewPlanOptions o;
  o.acquisition = acquisition;
  o.num_views = NumViewsOf(acquisition);
  return o;
}

std::string ViewPlanOptions::Check() const {
  const bool one_pass = acquisition == Acquisition::kStereo || acquisition == Acquisition::kTriStereo;
  if (one_pass && num_views != NumViewsOf(acquisition))
    return AcquisitionName(acquisition) + " has " + std::to_string(NumViewsOf(acquisition)) + " views";
  if (num_views < 2 || num_views > 64) return "num_views must be in [2, 64]";
  if (!(stereo_min_convergence_deg > 0 && stereo_min_convergence_deg <= stereo_max_convergence_deg &&
        stereo_max_convergence_deg <= 60))
    return "need 0 < stereo_min_convergence_deg <= stereo_max_convergence_deg <= 60";
  if (!(tristereo_min_convergence_deg > 0 && tristereo_min_convergence_deg <= tristereo_max_convergence_deg &&
        tristereo_max_convergence_deg <= 30))
    return "need 0 < tristereo_min_convergence_deg <= tristereo_max_convergence_deg <= 30";
  if (!(stereo_max_roll_deg >= 0 && stereo_max_roll_deg <= 30)) return "stereo_max_roll_deg must be in [0, 30]";
  if (!(tristereo_max_roll_deg >= 0 && tristereo_max_roll_deg <= 30))
    return "tristereo_max_roll_deg must be in [0, 30]";
  if (!(max_center_pitch_deg >= 0 && max_center_pitch_deg <= 10)) return "max_center_pitch_deg must be in [0, 10]";
  if (!(min_off_nadir_deg >= 0 && max_off_nadir_deg <= 45 && min_off_nadir_deg < max_off_nadir_deg))
    return "need 0 <= min_off_nadir_deg < max_off_nadir_deg <= 45";
  if (!(min_separation_deg >= 0)) return "min_separation_deg must be >= 0";
  if (!(first_year >= 1970 && first_year <= last_year && last_year <= 2100))
    return "need 1970 <= first_year <= last_year <= 2100";
  if (!(local_time_jitter_h >= 0 && local_time_jitter_h <= 2)) return "local_time_jitter_h must be in [0, 2]";
  return "";
}

Eigen::Vector3d SatelliteDirection(const Eigen::Vector2d& off_nadir_azimuth) {
  const double zen = std::asin(std::min(1.0, (kEarthR + kAltitude) / kEarthR *
                                                 std::sin(off_nadir_azimuth.x() * kDeg)));
  const double az = off_nadir_azimuth.y() * kDeg;
  return {std::sin(zen) * std::sin(az), std::sin(zen) * std::cos(az), std::cos(zen)};
}

double ViewIntersectionAngleDeg(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::acos(std::clamp(SatelliteDirection(a).dot(SatelliteDirection(b)), -1.0, 1.0)) / kDeg;
}

Eigen::Vector2d OffNadirAzimuthFromPitchRoll(double pitch_deg, double roll_deg, double track_heading_deg) {
  const double tp = std::tan(pitch_deg * kDeg), tr = std::tan(roll_deg * kDeg);
  const double off_nadir = std::atan(std::hypot(tp, tr)) / kDeg;
  // Look azimuth (satellite to scene) is heading + atan2(roll, pitch); the satellite is
  // seen from the scene in the opposite direction.
  double az = std::fmod(track_heading_deg + std::atan2(tr, tp) / kDeg + 180, 360.0);
  if (az < 0) az += 360;
  return {off_nadir, az};
}

Eigen::Vector2d SunElevationAzimuthDeg(double latitude_deg, double day_of_year, double local_solar_time_h) {
  const double decl = -23.44 * kDeg * std::cos(2 * M_PI * (day_of_year + 10) / 365.25);
  const double hour = 15 * (local_solar_time_h - 12) * kDeg, lat = latitude_deg * kDeg;
  const double east = -std::cos(decl) * std::sin(hour);
  const double north = std::sin(decl) * std::cos(lat) - std::cos(decl) * std::cos(hour) * std::sin(lat);
  const double up = std::sin(decl) * std::sin(lat) + std::cos(decl) * std::cos(hour) * std::cos(lat);
  double az = std::atan2(east, north) / kDeg;
  if (az < 0) az += 360;
  return {std::asin(std::clamp(up, -1.0, 1.0)) / kDeg, az};
}

ViewPlan PlanViewSet(const ViewPlanOptions& o, const Eigen::Vector2d& center_lon_lat, uint64_t seed) {
  const std::string why = o.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "ViewPlanOptions: " + why);
  Draw draw(seed);
  ViewPlan plan;
  switch (o.acquisition) {
    case Acquisition::kStereo: plan.views = PlanStereo(o, center_lon_lat, &draw); break;
    case Acquisition::kTriStereo: plan.views = PlanTriStereo(o, center_lon_lat, &draw); break;
    case Acquisition::kMultiDate:
    case Acquisition::kJax: plan.views = PlanMultiDate(o, center_lon_lat, &draw); break;
  }
  for (const PlannedView& v : plan.views)
    SATMESH_CHECK(v.off_nadir_azimuth_deg.x() <= 45, ErrorCode::kInvalidArgument,
                  "view plan: off-nadir " + std::to_string(v.off_nadir_azimuth_deg.x()) + " deg over 45");
  return plan;
}

}  // namespace satmesh::synth
