#include "core/refine/pairs.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace satmesh {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A view looking down at `off_nadir_deg` from azimuth `azimuth_deg` (satellite side),
// covering the whole 100 m surface unless a footprint is given.
PairCandidateView View(double off_nadir_deg, double azimuth_deg) {
  PairCandidateView v;
  const double o = off_nadir_deg * kDeg, a = azimuth_deg * kDeg;
  v.direction = -Eigen::Vector3d(std::sin(o) * std::sin(a), std::sin(o) * std::cos(a), std::cos(o));
  v.contrast = 0.2;
  v.footprint = Eigen::AlignedBox2d(Eigen::Vector2d(-60, -60), Eigen::Vector2d(60, 60));
  return v;
}

const Eigen::AlignedBox2d kSurface(Eigen::Vector2d(-50, -50), Eigen::Vector2d(50, 50));

// Along-track stereo: fore and aft at +-half the convergence.
std::vector<PairCandidateView> AlongTrack(std::initializer_list<double> off_nadir_signed) {
  std::vector<PairCandidateView> views;
  for (double o : off_nadir_signed) views.push_back(View(std::abs(o), o >= 0 ? 10 : 190));
  return views;
}

int Degree(const PairSelection& s, int v) {
  int d = 0;
  for (const auto& p : s.pairs) d += p.i == v || p.j == v;
  return d;
}

bool Connected(const PairSelection& s, int n) {
  std::set<int> reached{s.pairs.empty() ? 0 : s.pairs.front().i};
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& p : s.pairs)
      if (reached.count(p.i) != reached.count(p.j)) reached.insert({p.i, p.j}), grew = true;
  }
  return int(reached.size()) == n;
}

TEST(PairOptions, DefaultsAreValid) { EXPECT_EQ(PairOptions().Check(), ""); }

TEST(PairOptions, InvalidValuesAreNamed) {
  PairOptions o;
  o.optimal_angle_deg = 80;
  EXPECT_NE(o.Check().find("optimal_pair_angle_deg"), std::string::npos);
  o = PairOptions();
  o.min_overlap = 1.5;
  EXPECT_NE(o.Check().find("min_pair_overlap must be in [0, 1], got 1.5"), std::string::npos);
  o = PairOptions();
  o.partners_per_view = 0;
  EXPECT_NE(o.Check().find("pair_partners_per_view must be >= 1, got 0"), std::string::npos);
}

TEST(SelectPairs, WideStereoPairIsRefined) {
  // Pléiades / WorldView in-track stereo: 15, 25 and 35 degrees of convergence.
  for (double gamma : {15.0, 25.0, 35.0}) {
    const auto views = AlongTrack({gamma / 2, -gamma / 2});
    const PairSelection s = SelectPairs(views, kSurface, PairOptions());
    ASSERT_EQ(s.pairs.size(), 1u) << gamma << ": " << s.refusal;
    EXPECT_NEAR(s.pairs[0].angle_deg, gamma, 0.01);
    EXPECT_GT(s.pairs[0].score, 0.5);
  }
}

TEST(SelectPairs, NarrowOnlyUsesTheNarrowPairsButScoresThemLow) {
  // Three views within 4 degrees of each other: usable, but they constrain height weakly.
  const auto views = AlongTrack({1.0, -1.5, 3.5});
  const PairSelection s = SelectPairs(views, kSurface, PairOptions());
  ASSERT_EQ(s.pairs.size(), 3u);
  for (const auto& p : s.pairs) EXPECT_LT(p.score, 0.25) << p.i << "-" << p.j;
}

TEST(SelectPairs, ConvergenceUnderTwoDegreesIsRefusedWithTheReason) {
  const auto views = AlongTrack({0.5, -0.5});
  const PairSelection s = SelectPairs(views, kSurface, PairOptions());
  EXPECT_TRUE(s.pairs.empty());
  EXPECT_NE(s.refusal.find("min_pair_angle_deg"), std::string::npos) << s.refusal;
}

TEST(SelectPairs, ViewsThatDoNotOverlapAreRefusedWithTheReason) {
  auto views = AlongTrack({10, -10});
  views[0].footprint = Eigen::AlignedBox2d(Eigen::Vector2d(-300, -50), Eigen::Vector2d(-100, 50));
  const PairSelection s = SelectPairs(views, kSurface, PairOptions());
  EXPECT_TRUE(s.pairs.empty());
  EXPECT_NE(s.refusal.find("do not overlap"), std::string::npos) << s.refusal;
}

TEST(SelectPairs, LowContrastViewIsDropped) {
  auto views = AlongTrack({10, -10, 0});
  views[2].contrast = 0.001;
  const PairSelection s = SelectPairs(views, kSurface, PairOptions());
  ASSERT_EQ(s.pairs.size(), 1u);
  EXPECT_EQ(s.pairs[0].i, 0);
  EXPECT_EQ(s.pairs[0].j, 1);
}

TEST(SelectPairs, TriStereoUsesAllThreePairs) {
  const auto views = AlongTrack({-12, 0.5, 13});
  const PairSelection s = SelectPairs(views, kSurface, PairOptions());
  ASSERT_EQ(s.pairs.size(), 3u);
  // The outer pair (25 deg) is the best one: full precision, within the optimum's reach.
  const StereoPair* outer = nullptr;
  for (const auto& p : s.pairs)
    if (p.i == 0 && p.j == 2) outer = &p;
  ASSERT_NE(outer, nullptr);
  EXPECT_NEAR(outer->angle_deg, 25, 0.5);
}

TEST(SelectPairs, MixedSetGivesEveryViewPartnersAndIsConnected) {
  // Multi-date: 8 views from anywhere, off-nadir 5-35 degrees; two of them (6, 7) wide
  // from all others except each other.
  std::vector<PairCandidateView> views = {View(8, 20),   View(15, 60),  View(25, 100),
                                          View(12, 150), View(30, 200), View(20, 260),
                                          View(35, 320), View(33, 340)};
  const PairSelection s = SelectPairs(views, kSurface, PairOptions());
  EXPECT_TRUE(s.unpaired_views.empty());
  EXPECT_TRUE(Connected(s, 8));
  for (int v = 0; v < 8; ++v) {
    EXPECT_GE(Degree(s, v), 2) << v;
    EXPECT_LE(Degree(s, v), PairOptions().max_pairs_per_image) << v;
  }
  EXPECT_LE(int(s.pairs.size()), 12);  // the budget: max(10, 1.5 * 8)
  for (const auto& p : s.pairs) {
    EXPECT_GE(p.angle_deg, 2);
    EXPECT_LE(p.angle_deg, 60);
  }
}

TEST(SelectPairs, TwoGroupsThatCannotBeLinkedAreBothPaired) {
  // Two stereo pairs from opposite sides, 80-90 degrees apart: no pair links them.
  std::vector<PairCandidateView> views = {View(40, 90), View(45, 95), View(40, 270), View(45, 265)};
  const PairSelection s = SelectPairs(views, kSurface, PairOptions());
  ASSERT_EQ(s.pairs.size(), 2u);
  EXPECT_TRUE(s.unpaired_views.empty());
}

TEST(SelectPairs, BudgetAndCapHold) {
  std::vector<PairCandidateView> views;
  for (int k = 0; k < 26; ++k) views.push_back(View(5 + (k * 7) % 30, k * 360.0 / 26));
  PairOptions o;
  const PairSelection s = SelectPairs(views, kSurface, o);
  EXPECT_EQ(int(s.pairs.size()), 39);  // 1.5 per view
  EXPECT_TRUE(Connected(s, 26));
  for (int v = 0; v < 26; ++v) EXPECT_LE(Degree(s, v), o.max_pairs_per_image);
  o.max_pairs = 30;
  EXPECT_EQ(int(SelectPairs(views, kSurface, o).pairs.size()), 30);
}

TEST(PairScore, SunAndDateDifferencesLowerTheScore) {
  PairCandidateView a = View(10, 10), b = View(10, 190);
  const double angle = IntersectionAngleDeg(a.direction, b.direction);
  const double plain = PairScore(a, b, angle, 1.0, PairOptions());
  a.sun_elevation_deg = 60, a.sun_azimuth_deg = 140, a.time_s = 0;
  b.sun_elevation_deg = 60, b.sun_azimuth_deg = 140, b.time_s = 86400;
  const double same_day = PairScore(a, b, angle, 1.0, PairOptions());
  EXPECT_NEAR(same_day, plain, 0.01);
  b.sun_elevation_deg = 30, b.sun_azimuth_deg = 170, b.time_s = 200 * 86400;
  const double other_season = PairScore(a, b, angle, 1.0, PairOptions());
  EXPECT_LT(other_season, 0.6 * plain);
}

TEST(PairScore, PrecisionRisesToTheOptimumThenOcclusionLowersIt) {
  const PairOptions o;
  const PairCandidateView a, b;
  EXPECT_NEAR(PairScore(a, b, 5, 1, o), 0.25, 1e-9);
  EXPECT_NEAR(PairScore(a, b, 20, 1, o), 1.0, 1e-9);
  EXPECT_NEAR(PairScore(a, b, 60, 1, o), 0.5, 1e-9);
  EXPECT_NEAR(PairScore(a, b, 20, 0.5, o), 0.5, 1e-9);
}

TEST(FootprintOverlap, FractionOfTheSurface) {
  const Eigen::AlignedBox2d a(Eigen::Vector2d(-50, -50), Eigen::Vector2d(0, 50));
  const Eigen::AlignedBox2d b(Eigen::Vector2d(-25, -50), Eigen::Vector2d(50, 50));
  EXPECT_NEAR(FootprintOverlap(a, b, kSurface), 0.25, 1e-12);
  EXPECT_NEAR(FootprintOverlap(Eigen::AlignedBox2d(), b, kSurface), 0.75, 1e-12);
}

TEST(FacadeVisibility, IsTheHorizontalReachTowardsTheFacadesNormal) {
  const PairCandidateView east = View(30, 90);  // satellite to the east, 30 deg off nadir
  EXPECT_NEAR(FacadeVisibility(east, 90), 0.5, 1e-9);                      // sin 30
  EXPECT_NEAR(FacadeVisibility(east, 45), 0.5 * std::cos(45 * kDeg), 1e-9);
  EXPECT_EQ(FacadeVisibility(east, 270), 0.0);  // it sees the back of west-facing walls
  EXPECT_NEAR(FacadeVisibility(View(0, 90), 90), 0.0, 1e-9);  // nadir sees no wall
}

// Two views east of the scene and two west, and a budget of 5 pairs: the four cross pairs
// (44-48 degrees) score far higher than the two same-side ones (4 degrees: weak height
// precision), so by score alone the selection would take the four cross pairs and one
// same-side pair; but only a same-side pair sees that side's walls, so it takes both.
TEST(SelectPairs, CoversFacadeDirectionsThatOnlySameSidePairsSee) {
  const std::vector<PairCandidateView> views = {View(20, 88), View(24, 92), View(20, 268),
                                                View(24, 272)};
  PairOptions o;
  o.max_pairs = 5;
  const PairSelection s = SelectPairs(views, kSurface, o);
  ASSERT_EQ(s.pairs.size(), 5u);
  std::set<std::pair<int, int>> chosen;
  for (const auto& p : s.pairs) chosen.insert({p.i, p.j});
  EXPECT_TRUE(chosen.count({0, 1})) << "east walls";
  EXPECT_TRUE(chosen.count({2, 3})) << "west walls";
  double best_cross = 0;
  for (const auto& p : s.pairs)
    if (p.i / 2 != p.j / 2) best_cross = std::max(best_cross, p.score);
  for (const auto& p : s.pairs) {
    if (p.i / 2 != p.j / 2) continue;
    EXPECT_LT(p.angle_deg, 5) << p.i << "-" << p.j;
    EXPECT_LT(p.score, 0.5 * best_cross);
  }
}

}  // namespace
}  // namespace satmesh
