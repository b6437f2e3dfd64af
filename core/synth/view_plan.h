#pragma once
// Acquisition geometries of real satellite collections for synthetic scenes (see
// ../shared/ACQUISITIONS.md): one-pass along-track stereo (WorldView/Pléiades), one-pass
// tri-stereo (Pléiades), and multi-date archives (one image per pass, any azimuth, the sun
// of each date; the JAX-like 26-view set). Views are drawn from these distributions only:
// nothing here knows the refinement's pair selection.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace satmesh::synth {

enum class Acquisition {
  kStereo,     // 2 views, one pass, along track
  kTriStereo,  // 3 views, one pass: fore / near-nadir / aft
  kMultiDate,  // one view per pass, different dates (6 by default)
  kJax,        // the 26-view multi-date archive (IARPA MVS3DM Jacksonville-like)
};
std::string AcquisitionName(Acquisition a);  // "stereo", "tristereo", "multidate", "jax"
std::optional<Acquisition> ParseAcquisition(const std::string& name);

struct ViewPlanOptions {
  Acquisition acquisition = Acquisition::kMultiDate;
  int num_views = 6;  // stereo: 2, tristereo: 3, multi-date: [2, 64] (ForAcquisition sets it)
  // One pass (stereo, tristereo): track heading drawn as descending (190 +- 5 deg) or
  // ascending (350 +- 5 deg); a common across-track roll of the pass.
  double stereo_min_convergence_deg = 15;     // stereo pair's convergence angle, drawn
  double stereo_max_convergence_deg = 35;     //   uniformly, 0 < min <= max <= 60
  double stereo_max_roll_deg = 15;            // |roll| off the track, uniform in [0, max], [0, 30]
  double tristereo_min_convergence_deg = 6;   // each outer view with the near-nadir one,
  double tristereo_max_convergence_deg = 15;  //   drawn independently, 0 < min <= max <= 30
  double tristereo_max_roll_deg = 5;          // keeps the middle view near nadir, [0, 30]
  double max_center_pitch_deg = 3;            // along-track asymmetry of the pass, [0, 10]
  // Multi-date: per pass, azimuth uniform in [0, 360), off-nadir uniform in the range.
  double min_off_nadir_deg = 5, max_off_nadir_deg = 35;  // 0 <= min < max <= 45
  double min_separation_deg = 1;  // two passes never coincide: redraw a view closer, >= 0
  // Dates and sun: descending passes at local solar time 10:30, ascending ones at 13:30
  // (sun-synchronous orbits), +- local_time_jitter_h (off-track targets); dates uniform over
  // [first_year, last_year]. The sun follows from the date, time and the scene's latitude.
  int first_year = 2014, last_year = 2016;  // 1970 <= first <= last <= 2100
  double local_time_jitter_h = 0.3;         // [0, 2]
  std::string Check() const;
};

// The defaults of a collection: num_views (2, 3, 6, 26) and the rest as above.
ViewPlanOptions ForAcquisition(Acquisition acquisition);

struct PlannedView {
  Eigen::Vector2d off_nadir_azimuth_deg{0, 0};  // at the satellite; satellite azimuth from the scene
  double track_heading_deg = 190;               // ground-track heading, clockwise from N
  int pass = 0;                                 // views of one pass share it (and date, sun)
  double acquisition_unix_s = 0;                // first line time, UTC
  double sun_elevation_deg = 60, sun_azimuth_deg = 135;
  double pitch_deg = 0, roll_deg = 0;           // one pass: look angles along / across track
};

struct ViewPlan {
  std::vector<PlannedView> views;
};

// Deterministic in seed. center_lon_lat: the scene centre (sun position, local time).
// Throws Error{kInvalidArgument} on invalid options.
ViewPlan PlanViewSet(const ViewPlanOptions& options, const Eigen::Vector2d& center_lon_lat,
                     uint64_t seed);

// Unit vector from the scene towards a satellite at `off_nadir_azimuth_deg` on a 600 km
// orbit (spherical Earth), x east, y north, z up.
Eigen::Vector3d SatelliteDirection(const Eigen::Vector2d& off_nadir_azimuth_deg);
// Angle (deg) between the viewing directions of two views.
double ViewIntersectionAngleDeg(const Eigen::Vector2d& off_nadir_azimuth_a,
                                const Eigen::Vector2d& off_nadir_azimuth_b);
// (off-nadir, satellite azimuth) of a look at pitch (along track, > 0: forward) and roll
// (across track, > 0: right of the track) from a satellite on `track_heading_deg`.
Eigen::Vector2d OffNadirAzimuthFromPitchRoll(double pitch_deg, double roll_deg,
                                             double track_heading_deg);
// Sun (elevation, azimuth) in deg at a latitude, day of year [1, 366] and local solar time
// (h); declination from the day, no equation of time.
Eigen::Vector2d SunElevationAzimuthDeg(double latitude_deg, double day_of_year,
                                       double local_solar_time_h);

}  // namespace satmesh::synth
