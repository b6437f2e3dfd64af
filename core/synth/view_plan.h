#pragma once
// View planning for synthetic scenes: viewing directions (off-nadir, azimuth) spread the
// way multi-date satellite collections are (azimuths around the circle, off-nadir 5-35°),
// chosen so that the refinement's pair selection (core/refine/pairs.h) gives every view
// stereo partners.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace satmesh::synth {

struct ViewPlanOptions {
  int num_views = 10;                          // [2, 64]
  double min_off_nadir_deg = 5;                // off-nadir range at the satellite, deg,
  double max_off_nadir_deg = 35;               //   0 <= min < max <= 45
  double azimuth_spread_deg = 360;             // azimuths stratified over this sector, (0, 360]
  double off_nadir_stratum_width = 2;          // view i's off-nadir in its own stratum of this
                                               // width (units of range/N), >= 0; 0: free
  double azimuth_jitter = 0.8;                 // jitter as a fraction of a stratum, [0, 1]
  double min_pair_angle_deg = 5;               // the refinement's pair window, deg, 0 < min < max
  double max_pair_angle_deg = 13;
  double window_margin_deg = 0.5;              // planned pairs keep this far inside the window, >= 0
  int max_pairs_per_image = 4;                 // the refinement's cap on pairs per image, >= 1
  int min_partners = 2;                        // selected pairs per view, >= 1 (capped by N-1 and the cap)
  int target_pairs = 0;                        // at least this many pairs selected in all (capped by N and the cap), >= 0
  double min_separation_deg = 3;               // no two views closer than this, deg, >= 0
  int iterations = 4000;                       // local search steps per restart, >= 1
  std::string Check() const;
};

struct ViewPlan {
  std::vector<Eigen::Vector2d> off_nadir_azimuth_deg;  // per view
  std::vector<std::pair<int, int>> pairs;              // SelectPairs on the planned directions
  int candidate_pairs = 0;                             // pairs inside the (unshrunk) window
};

// Deterministic in seed. Throws Error{kInvalidArgument} when no plan satisfies the
// partner constraint (e.g. too few views for the azimuth spread).
ViewPlan PlanViewSet(const ViewPlanOptions& options, uint64_t seed);

// Unit vector from the scene towards a satellite at `off_nadir_azimuth_deg` on a 600 km
// orbit (spherical Earth), x east, y north, z up.
Eigen::Vector3d SatelliteDirection(const Eigen::Vector2d& off_nadir_azimuth_deg);
// Angle (deg) between the viewing directions of two views.
double ViewIntersectionAngleDeg(const Eigen::Vector2d& off_nadir_azimuth_a,
                                const Eigen::Vector2d& off_nadir_azimuth_b);

}  // namespace satmesh::synth
