// Acquisition geometries: the numbers each collection is drawn with (ACQUISITIONS.md).
#include "core/synth/view_plan.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/common/error.h"

namespace satmesh::synth {
namespace {

const Eigen::Vector2d kJacksonville(-81.6557, 30.3322);

double Angle(const PlannedView& a, const PlannedView& b) {
  return ViewIntersectionAngleDeg(a.off_nadir_azimuth_deg, b.off_nadir_azimuth_deg);
}

// Heading of a sun-synchronous pass: descending ~190 or ascending ~350, +-5 deg.
bool NearPolarHeading(double h) { return std::abs(h - 190) <= 5 || std::abs(h - 350) <= 5; }

// Angle (deg, [0, 90]) between the horizontal baseline of two views and the track.
double BaselineOffTrackDeg(const PlannedView& a, const PlannedView& b) {
  const Eigen::Vector3d d = SatelliteDirection(a.off_nadir_azimuth_deg) - SatelliteDirection(b.off_nadir_azimuth_deg);
  const double h = a.track_heading_deg * M_PI / 180;
  const Eigen::Vector2d track(std::sin(h), std::cos(h));  // east, north
  const double c = std::abs(d.head<2>().normalized().dot(track));
  return std::acos(std::min(1.0, c)) * 180 / M_PI;
}

TEST(OffNadirAzimuthFromPitchRoll, ForwardAndSidewaysLooks) {
  // Descending pass heading 190: a forward look sees the scene from the north-north-east.
  const Eigen::Vector2d fore = OffNadirAzimuthFromPitchRoll(10, 0, 190);
  EXPECT_NEAR(fore.x(), 10, 1e-9);
  EXPECT_NEAR(fore.y(), 10, 1e-9);
  // Heading north, looking right (east): the satellite is west of the scene.
  const Eigen::Vector2d right = OffNadirAzimuthFromPitchRoll(0, 10, 0);
  EXPECT_NEAR(right.x(), 10, 1e-9);
  EXPECT_NEAR(right.y(), 270, 1e-9);
  // Combined: tan^2 adds.
  EXPECT_NEAR(OffNadirAzimuthFromPitchRoll(10, 10, 0).x(),
              std::atan(std::hypot(std::tan(0.1745329), std::tan(0.1745329))) * 180 / M_PI, 1e-4);
}

TEST(SunElevationAzimuthDeg, SolsticesAndEquinoxNoon) {
  const Eigen::Vector2d noon = SunElevationAzimuthDeg(30, 81, 12);  // ~equinox
  EXPECT_NEAR(noon.x(), 60, 0.5);
  EXPECT_NEAR(noon.y(), 180, 1e-6);
  // Jacksonville, 10:30 local solar time: summer high in the east-south-east, winter low
  // in the south-south-east.
  const Eigen::Vector2d summer = SunElevationAzimuthDeg(30.33, 172, 10.5);
  EXPECT_NEAR(summer.x(), 68.8, 0.5);
  EXPECT_NEAR(summer.y(), 103.6, 1.0);
  const Eigen::Vector2d winter = SunElevationAzimuthDeg(30.33, 355, 10.5);
  EXPECT_NEAR(winter.x(), 32.1, 0.5);
  EXPECT_NEAR(winter.y(), 155.5, 1.0);
}

TEST(PlanViewSet, StereoIsOnePassAlongTrackConverging15To35) {
  double lo = 90, hi = 0, roll_hi = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const ViewPlan plan = PlanViewSet(ForAcquisition(Acquisition::kStereo), kJacksonville, seed);
    ASSERT_EQ(plan.views.size(), 2u);
    const PlannedView &fore = plan.views[0], &aft = plan.views[1];
    const double gamma = Angle(fore, aft);
    EXPECT_GE(gamma, 15 - 1e-6) << seed;
    EXPECT_LE(gamma, 35 + 1e-6) << seed;
    lo = std::min(lo, gamma), hi = std::max(hi, gamma);
    // One pass: same heading, roll, sun, pass; fore taken first, seconds apart.
    EXPECT_TRUE(NearPolarHeading(fore.track_heading_deg)) << fore.track_heading_deg;
    EXPECT_EQ(fore.track_heading_deg, aft.track_heading_deg);
    EXPECT_EQ(fore.pass, aft.pass);
    EXPECT_EQ(fore.roll_deg, aft.roll_deg);
    EXPECT_LE(std::abs(fore.roll_deg), 15);
    roll_hi = std::max(roll_hi, std::abs(fore.roll_deg));
    EXPECT_GT(fore.pitch_deg, aft.pitch_deg);
    EXPECT_EQ(fore.sun_elevation_deg, aft.sun_elevation_deg);
    EXPECT_EQ(fore.sun_azimuth_deg, aft.sun_azimuth_deg);
    EXPECT_LT(fore.acquisition_unix_s, aft.acquisition_unix_s);
    EXPECT_LT(aft.acquisition_unix_s - fore.acquisition_unix_s, 120);
    // Along track: the baseline runs with the ground track.
    EXPECT_LT(BaselineOffTrackDeg(fore, aft), 5) << seed;
    for (const auto& v : plan.views) EXPECT_LE(v.off_nadir_azimuth_deg.x(), 30);
  }
  EXPECT_LT(lo, 19);  // drawn over the range, not fixed
  EXPECT_GT(hi, 31);
  EXPECT_GT(roll_hi, 8);
}

TEST(PlanViewSet, TriStereoHasANearNadirViewAndOuterPairs6To15) {
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const ViewPlan plan = PlanViewSet(ForAcquisition(Acquisition::kTriStereo), kJacksonville, seed);
    ASSERT_EQ(plan.views.size(), 3u);
    const PlannedView &fore = plan.views[0], &mid = plan.views[1], &aft = plan.views[2];
    EXPECT_LE(mid.off_nadir_azimuth_deg.x(), 6) << seed;  // |pitch| <= 3, |roll| <= 5
    for (const PlannedView* outer : {&fore, &aft}) {
      const double gamma = Angle(*outer, mid);
      EXPECT_GE(gamma, 6 - 1e-6) << seed;
      EXPECT_LE(gamma, 15 + 1e-6) << seed;
      EXPECT_LT(BaselineOffTrackDeg(*outer, mid), 5) << seed;
      EXPECT_EQ(outer->pass, mid.pass);
      EXPECT_EQ(outer->sun_azimuth_deg, mid.sun_azimuth_deg);
      EXPECT_EQ(outer->track_heading_deg, mid.track_heading_deg);
    }
    // The wide outer pair: the two angles add up along the track.
    EXPECT_GE(Angle(fore, aft), 12 - 1e-3) << seed;
    EXPECT_LE(Angle(fore, aft), 30 + 1e-3) << seed;
    EXPECT_LT(fore.acquisition_unix_s, mid.acquisition_unix_s);
    EXPECT_LT(mid.acquisition_unix_s, aft.acquisition_unix_s);
  }
}

// Multi-date: any azimuth, off-nadir 5-35, one pass per view in date order, the sun of each
// date (shadows move), no two passes within 1 deg.
void ExpectMultiDate(const ViewPlan& plan, int num_views, uint64_t seed) {
  ASSERT_EQ(int(plan.views.size()), num_views);
  std::set<long long> days;
  double el_lo = 90, el_hi = 0, az_lo = 360, az_hi = 0;
  for (int i = 0; i < num_views; ++i) {
    const PlannedView& v = plan.views[i];
    EXPECT_GE(v.off_nadir_azimuth_deg.x(), 5) << seed;
    EXPECT_LE(v.off_nadir_azimuth_deg.x(), 35) << seed;
    EXPECT_GE(v.off_nadir_azimuth_deg.y(), 0);
    EXPECT_LT(v.off_nadir_azimuth_deg.y(), 360);
    EXPECT_EQ(v.pass, i);
    EXPECT_TRUE(NearPolarHeading(v.track_heading_deg));
    if (i > 0) EXPECT_GT(v.acquisition_unix_s, plan.views[i - 1].acquisition_unix_s);
    // 2014-2016, around 10:30 or 13:30 local (UTC-5.44 h).
    EXPECT_GE(v.acquisition_unix_s, 1388534400);  // 2014-01-01
    EXPECT_LT(v.acquisition_unix_s, 1483228800);  // 2017-01-01
    days.insert((long long)std::floor(v.acquisition_unix_s / 86400));
    // Mid-latitude mornings and early afternoons: the sun in the southern sky, 30-70 deg up.
    EXPECT_GE(v.sun_elevation_deg, 28) << seed;
    EXPECT_LE(v.sun_elevation_deg, 75) << seed;
    EXPECT_GE(v.sun_azimuth_deg, 90) << seed;
    EXPECT_LE(v.sun_azimuth_deg, 270) << seed;
    el_lo = std::min(el_lo, v.sun_elevation_deg), el_hi = std::max(el_hi, v.sun_elevation_deg);
    az_lo = std::min(az_lo, v.sun_azimuth_deg), az_hi = std::max(az_hi, v.sun_azimuth_deg);
    for (int j = 0; j < i; ++j) EXPECT_GE(Angle(v, plan.views[j]), 1) << seed;
  }
  EXPECT_GE(int(days.size()), num_views - 1) << seed;  // different dates
  EXPECT_GT(el_hi - el_lo, 3) << seed;                 // the sun moves between dates
  EXPECT_GT(az_hi - az_lo, 5) << seed;
}

TEST(PlanViewSet, MultiDateViewsComeFromDifferentPassesAndSuns) {
  for (uint64_t seed = 1; seed <= 20; ++seed)
    ExpectMultiDate(PlanViewSet(ForAcquisition(Acquisition::kMultiDate), kJacksonville, seed), 6, seed);
}

TEST(PlanViewSet, JaxSpreadsAroundTheCircleAndOverOffNadir) {
  const ViewPlan plan = PlanViewSet(ForAcquisition(Acquisition::kJax), kJacksonville, 1);
  ExpectMultiDate(plan, 26, 1);
  double lo = 90, hi = 0;
  int quadrant[4] = {};
  for (const auto& v : plan.views) {
    lo = std::min(lo, v.off_nadir_azimuth_deg.x()), hi = std::max(hi, v.off_nadir_azimuth_deg.x());
    ++quadrant[int(v.off_nadir_azimuth_deg.y() / 90) % 4];
  }
  EXPECT_LT(lo, 10);
  EXPECT_GT(hi, 28);
  for (int q : quadrant) EXPECT_GE(q, 1);
}

TEST(PlanViewSet, DeterministicInSeed) {
  for (Acquisition a : {Acquisition::kStereo, Acquisition::kTriStereo, Acquisition::kMultiDate}) {
    const ViewPlan p1 = PlanViewSet(ForAcquisition(a), kJacksonville, 7);
    const ViewPlan p2 = PlanViewSet(ForAcquisition(a), kJacksonville, 7);
    const ViewPlan p3 = PlanViewSet(ForAcquisition(a), kJacksonville, 8);
    ASSERT_EQ(p1.views.size(), p2.views.size());
    for (size_t i = 0; i < p1.views.size(); ++i) {
      EXPECT_EQ(p1.views[i].off_nadir_azimuth_deg, p2.views[i].off_nadir_azimuth_deg);
      EXPECT_EQ(p1.views[i].acquisition_unix_s, p2.views[i].acquisition_unix_s);
    }
    EXPECT_NE(p1.views[0].off_nadir_azimuth_deg, p3.views[0].off_nadir_azimuth_deg);
  }
}

TEST(ViewPlanOptions, DefaultsAreValidAndCountsFollowTheCollection) {
  for (Acquisition a : {Acquisition::kStereo, Acquisition::kTriStereo, Acquisition::kMultiDate, Acquisition::kJax}) {
    EXPECT_EQ(ForAcquisition(a).Check(), "") << AcquisitionName(a);
    EXPECT_EQ(ParseAcquisition(AcquisitionName(a)), a);
  }
  EXPECT_FALSE(ParseAcquisition("quadstereo").has_value());
  EXPECT_EQ(ForAcquisition(Acquisition::kJax).num_views, 26);
  ViewPlanOptions o = ForAcquisition(Acquisition::kTriStereo);
  o.num_views = 4;
  EXPECT_NE(o.Check(), "");
  o = ForAcquisition(Acquisition::kStereo);
  o.stereo_min_convergence_deg = 40;  // above the max
  EXPECT_NE(o.Check(), "");
  EXPECT_THROW(PlanViewSet(o, kJacksonville, 1), Error);
  o = ForAcquisition(Acquisition::kMultiDate);
  o.num_views = 64;
  o.min_separation_deg = 30;  // no room for 64 passes 30 deg apart
  EXPECT_THROW(PlanViewSet(o, kJacksonville, 1), Error);
}

}  // namespace
}  // namespace satmesh::synth
