#pragma once
// Stereo pair selection (paper 4.2, generalised to the view sets users have): every pair
// of usable views whose footprints overlap the surface and whose viewing directions
// converge by min..max degrees is a candidate; candidates are ranked by what they
// contribute (PairScore: height precision, occlusion, overlap, similarity of the two
// acquisitions); the selection first connects every usable view (a maximum spanning
// forest, so that the per-view bias estimation reaches every refined view), then gives
// each view partners, then fills a budget of pairs that keeps the speed; partners and
// budget favour pairs that cover facade directions no selected pair covers yet.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/refine/refine_options.h"

namespace satmesh {

struct PairCandidateView {
  Eigen::Vector3d direction{0, 0, -1};  // unit viewing direction (towards the ground)
  double contrast = 0;                   // std of the normalised image
  // Ground footprint of the image window at the surface's mid height, frame x/y (m);
  // empty: unknown (taken to cover the surface).
  Eigen::AlignedBox2d footprint;
  // Acquisition (image metadata); NaN where unknown.
  double sun_elevation_deg = std::numeric_limits<double>::quiet_NaN();
  double sun_azimuth_deg = std::numeric_limits<double>::quiet_NaN();
  double time_s = std::numeric_limits<double>::quiet_NaN();  // unix seconds
};

struct StereoPair {
  int i = 0, j = 0;        // views, i < j
  double angle_deg = 0;    // intersection angle of the central viewing directions
  double overlap = 0;      // fraction of the surface box both footprints cover, [0, 1]
  double score = 0;        // PairScore, (0, 1]
};

struct PairSelection {
  std::vector<StereoPair> pairs;    // selected, sorted by (i, j)
  int num_candidates = 0;           // pairs that passed angle, overlap and contrast
  std::vector<int> unpaired_views;  // usable views left without a partner
  std::string refusal;              // no pair at all: why (names views and angles)
  std::vector<std::pair<int, int>> IndexPairs() const;
  // The same, highest score first (the order the bias estimation takes neighbours in).
  std::vector<std::pair<int, int>> IndexPairsBestFirst() const;
};

double IntersectionAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

// What a candidate pair contributes, (0, 1]: the product of
//  - height precision: min(1, angle / optimal_angle) (B/H grows with the angle; beyond
//    the optimum the visibility test, not precision, limits a pair),
//  - occlusion: 1 up to the optimal angle, falling linearly to 0.5 at max_angle_deg,
//  - overlap: the fraction of the surface both images see,
//  - sun: 0.25 + 0.75 exp(-(dsun / 25 deg)^2), dsun the angle between the sun directions
//    (shadows move between dates), 1 where unknown,
//  - date: 0.5 + 0.5 exp(-ddays / 180) (vegetation, cars, construction), 1 where unknown.
double PairScore(const PairCandidateView& a, const PairCandidateView& b, double angle_deg,
                 double overlap, const PairOptions& options);

// Fraction of `surface` (frame x/y) covered by both footprints (empty footprint: all).
double FootprintOverlap(const Eigen::AlignedBox2d& a, const Eigen::AlignedBox2d& b,
                        const Eigen::AlignedBox2d& surface);

// How well a view sees facades whose outward normal points to `facade_azimuth_deg`
// (degrees clockwise from north): the horizontal component of its direction towards the
// satellite along that normal, sin(off-nadir) cos(azimuth difference), 0 where it sees
// their back. Steps 2 and 3 of the selection raise a pair's score by the facade
// directions it covers (both views see them) that the selected pairs do not yet.
double FacadeVisibility(const PairCandidateView& view, double facade_azimuth_deg);

// The selection described above; never throws. An empty result carries the reason.
PairSelection SelectPairs(const std::vector<PairCandidateView>& views,
                          const Eigen::AlignedBox2d& surface, const PairOptions& options);

}  // namespace satmesh
