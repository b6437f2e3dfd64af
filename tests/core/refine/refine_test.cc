#include "core/refine/refine.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/refine/height_confidence.h"
#include "core/refine/momentum.h"
#include "core/refine/refine_level.h"
#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

using testing::PlaneError;
using testing::SmallOptions;
using testing::SmallOptionsTwoPairs;

TEST(RefineOptions, DefaultsAreValid) { EXPECT_EQ(RefineOptions().Check(), ""); }

TEST(RefineOptions, InvalidValuesAreNamed) {
  RefineOptions o;
  o.zncc_window_radius = 0;
  EXPECT_NE(o.Check().find("zncc_window_radius"), std::string::npos);
  o = RefineOptions();
  o.pairs.max_angle_deg = 2;
  EXPECT_NE(o.Check().find("max_pair_angle_deg must be > min_pair_angle_deg"), std::string::npos);
  o = RefineOptions();
  o.step = -1;
  EXPECT_NE(o.Check().find("step"), std::string::npos);
  o = RefineOptions();
  o.hit_maps_every = 0;
  EXPECT_NE(o.Check().find("hit_maps_every"), std::string::npos);
}

TEST(Refine, GroundTruthStaysPut) {
  const testing::Plane plane;
  const auto input = testing::MakePlaneInput(plane, testing::DefaultViews(),
                                             testing::PlaneMesh(plane, 40, 1.0, 0.0));
  const RefineResult result = Refine(input, SmallOptions());
  const auto [mean, p95] = PlaneError(result.mesh, plane, 30);
  EXPECT_LT(mean, 0.05);  // 0.1 GSD
  EXPECT_LT(p95, 0.15);
  EXPECT_EQ(result.levels.size(), 3u);
}

// smooth_offsets: the thin-plate term acts on the offset from the start, so a mesh start's
// crease the images say nothing about (alpha 0: the thin-plate term alone) stays as it is;
// smoothing the surface itself rounds it off.
TEST(Refine, SmoothingTheOffsetsKeepsAMeshStartsCreases) {
  const testing::Plane plane;
  TriangleMesh ridge = testing::PlaneMesh(plane, 40, 1.0, 0.0);
  size_t top = 0;
  for (size_t v = 0; v < ridge.vertices.size(); ++v)
    if (std::abs(ridge.vertices[v].x()) < 0.5f) {
      ridge.vertices[v].z() += 1.f;  // a 1 m ridge along y
      if (std::abs(ridge.vertices[v].y()) < 0.5f) top = v;
    }
  RefineInput input = testing::MakePlaneInput(plane, testing::DefaultViews(), ridge);
  input.initial_is_mesh = true;
  RefineOptions o = SmallOptions();
  o.levels = 0;
  o.alpha = 0;
  o.grid_start = 1;  // the mesh's triangles as they are
  o.initial_sigma_gsd = 0;
  o.keep_initial_sigmas = 0;
  o.register_to_initial = 0;
  o.hold_unseen = false;
  ASSERT_EQ(o.smooth_offsets, -1);  // on for a mesh start
  const RefineResult kept = Refine(input, o);
  o.smooth_offsets = 0;
  const RefineResult smoothed = Refine(input, o);
  ASSERT_EQ(kept.mesh.vertices.size(), ridge.vertices.size());
  double largest_move = 0;
  for (size_t v = 0; v < ridge.vertices.size(); ++v)
    largest_move = std::max(largest_move, double((kept.mesh.vertices[v] - ridge.vertices[v]).norm()));
  EXPECT_LT(largest_move, 1e-4);
  EXPECT_LT(smoothed.mesh.vertices[top].z(), ridge.vertices[top].z() - 0.05f);
}

TEST(Refine, TiltedPlaneStartedMetresOffConverges) {
  const testing::Plane plane;
  const auto input = testing::MakePlaneInput(plane, testing::DefaultViews(),
                                             testing::PlaneMesh(plane, 40, 1.0, 3.0));
  const RefineResult result = Refine(input, SmallOptions());
  const auto [mean, p95] = PlaneError(result.mesh, plane, 30);
  EXPECT_LT(mean, 0.1);  // 0.2 GSD, from 6 GSD off
  EXPECT_LT(p95, 0.25);
  // Mean ZNCC rises at every level.
  for (const auto& level : result.levels)
    EXPECT_GT(level.mean_zncc.back(), level.mean_zncc.front()) << "level " << level.level;
}

// pairs_per_iteration: the middle iterations take the pairs in turn, one group each, and
// the last few take every pair again; the surface converges as with every pair every
// iteration. DefaultViews' 3 pairs of 3 views in 2 groups (2 and 1 pairs: at least half as
// many as the views), 2 levels of 30 / 15 iterations.
TEST(Refine, PairsTakenInTurnConvergeAsEveryPairDoes) {
  const testing::Plane plane;
  const auto input = testing::MakePlaneInput(plane, testing::DefaultViews(),
                                             testing::PlaneMesh(plane, 40, 1.0, 3.0));
  RefineOptions all = SmallOptions(), grouped = SmallOptions();
  all.pairs_per_iteration = 0;
  grouped.pairs_per_iteration = 1;
  const RefineResult a = Refine(input, all), b = Refine(input, grouped);
  ASSERT_EQ(a.pairs.size(), 3u);
  const auto [mean_a, p95_a] = PlaneError(a.mesh, plane, 30);
  const auto [mean_b, p95_b] = PlaneError(b.mesh, plane, 30);
  std::printf("every pair: mean %.4f p95 %.4f m; in turn: mean %.4f p95 %.4f m\n", mean_a, p95_a,
              mean_b, p95_b);
  EXPECT_LT(mean_b, 0.1);  // as TiltedPlaneStartedMetresOffConverges
  EXPECT_LT(p95_b, 0.25);
  // Every pair in one group also ends on both directions of each, which a grouped level
  // does not: within 2x (every pair / in turn: 0.067 / 0.060 m here in 2 groups, 0.065 /
  // 0.050 m in session 39's 3 groups of one; before session 33's hit maps, 0.047-0.050 /
  // 0.075-0.085 m).
  EXPECT_LT(mean_b, 2.0 * mean_a + 0.01);
  // The schedule: the first iteration both directions of every pair (6 pair-directions);
  // of the others, those before the last 3 one group in turn in one direction, the last 3
  // one direction of every pair; no pass after the last step. Every pair every iteration
  // (one group): the last iteration both directions again.
  const size_t group_size[2] = {PairGroup(b.pairs, 2, 0).size(), PairGroup(b.pairs, 2, 1).size()};
  ASSERT_EQ(group_size[0] + group_size[1], 3u);
  ASSERT_EQ(a.levels.size(), b.levels.size());
  for (size_t l = 0; l < b.levels.size(); ++l) {
    const int later = b.levels[l].iterations - 1;
    int grouped = 0;
    for (int it = 1; it <= later - 3; ++it) grouped += int(group_size[(it - 1) % 2]);
    EXPECT_EQ(a.levels[l].pair_directions, 6 + (later - 1) * 3 + 6) << "level " << l;
    EXPECT_EQ(b.levels[l].pair_directions, 6 + grouped + 3 * 3) << "level " << l;
  }
}

// The heavy ball carries what a vertex's last two moves agree on, per coordinate: the
// smaller where they have the same sign, nothing where they swing (a pair's two directions).
TEST(Refine, AgreedMoveCarriesOnlyWhatBothMovesAgreeOn) {
  const Eigen::Vector3f agreed =
      AgreedMove(Eigen::Vector3f(0.3f, -0.2f, 0.1f), Eigen::Vector3f(0.1f, 0.4f, 0.5f));
  EXPECT_FLOAT_EQ(agreed.x(), 0.1f);  // same sign: the smaller move
  EXPECT_FLOAT_EQ(agreed.y(), 0.f);   // a swing: nothing
  EXPECT_FLOAT_EQ(agreed.z(), 0.1f);
  EXPECT_EQ(AgreedMove(Eigen::Vector3f(-0.3f, 0.f, 0.2f), Eigen::Vector3f(-0.5f, 0.2f, 0.f)),
            Eigen::Vector3f(-0.3f, 0.f, 0.f));  // a coordinate that did not move carries nothing
}

// momentum (MomentumStep): a move every iteration agrees on is made in fewer iterations than
// by plain steps, where the steps are below the clamp (a plane started 2 GSD off, one level
// run once, no pull towards the start, a small step: the regime of weakly textured or weakly
// constrained surfaces), and the iterations still settle it (64 steps: 0.07 m; the plain
// steps 0.24 m).
TEST(Refine, MomentumMakesAConsistentMoveInFewerIterations) {
  const testing::Plane plane;
  const auto input = testing::MakePlaneInput(plane, testing::DefaultViews(),
                                             testing::PlaneMesh(plane, 40, 1.0, 1.0));
  RefineOptions plain = SmallOptions();
  plain.levels = 0;
  plain.initial_sigma_gsd = 0;
  plain.step = 0.1;
  plain.momentum = 0;
  plain.crease_pass = 0;  // one run of level 0: coarsest_iterations_factor x the iterations
  RefineOptions heavy = plain;
  heavy.momentum = 0.5;
  for (const int iterations : {10, 32}) {
    plain.iterations_per_level = heavy.iterations_per_level = iterations;
    const double a = PlaneError(Refine(input, plain).mesh, plane, 30).first;
    const double b = PlaneError(Refine(input, heavy).mesh, plane, 30).first;
    std::printf("%d iterations from 1 m: plain %.4f m, momentum 0.5 %.4f m\n", iterations, a, b);
    if (iterations == 10) {
      EXPECT_LT(b, 0.75 * a);  // the first two steps carry nothing
    }
    if (iterations == 32) {
      EXPECT_LT(b, 0.1);  // 0.2 GSD, as the tests above
    }
  }
}

// The default rasterized hit maps and Embree's ray casting give the same refinement.
TEST(Refine, RasterizedAndRayCastHitMapsAgree) {
  const testing::Plane plane;
  const auto input = testing::MakePlaneInput(plane, testing::DefaultViews(),
                                             testing::PlaneMesh(plane, 40, 1.0, 3.0));
  RefineOptions raycast = SmallOptionsTwoPairs();
  raycast.rasterize_hit_maps = false;
  const RefineResult a = Refine(input, SmallOptionsTwoPairs()), b = Refine(input, raycast);
  ASSERT_EQ(a.mesh.vertices.size(), b.mesh.vertices.size());
  ASSERT_EQ(a.levels.size(), b.levels.size());
  for (size_t l = 0; l < a.levels.size(); ++l)
    for (size_t k = 0; k < a.levels[l].mean_zncc.size(); ++k)
      EXPECT_NEAR(a.levels[l].mean_zncc[k], b.levels[l].mean_zncc[k], 1e-4) << "level " << l;
  // Vertices are compared with their nearest in the other mesh: SortSpatially reorders
  // them by position after each level, so float-level differences may permute them. The
  // largest difference is taken away from the mesh's border (40 m out): near it the two
  // draw the silhouette's pixels by different rules (the rasterizer's top-left rule,
  // Embree's watertight test), and a vertex there that few pixels see may move by a few
  // tenths of a GSD more in one (0.25 m once, at (40.06, 29.53), with the blocks' band
  // remeshed in pieces, session 38).
  std::vector<double> distance;
  double max_diff = 0, max_near_border = 0;
  for (const Eigen::Vector3f& p : a.mesh.vertices) {
    float nearest = std::numeric_limits<float>::infinity();
    for (const Eigen::Vector3f& q : b.mesh.vertices) nearest = std::min(nearest, (p - q).squaredNorm());
    distance.push_back(std::sqrt(nearest));
    double& max = std::max(std::abs(p.x()), std::abs(p.y())) < 38 ? max_diff : max_near_border;
    max = std::max(max, distance.back());
  }
  std::sort(distance.begin(), distance.end());
  const double p99 = distance[distance.size() * 99 / 100];
  std::printf("distance to the nearest vertex: median %.1e, p99 %.1e, max %.1e m (within 2 m "
              "of the border %.1e)\n", distance[distance.size() / 2], p99, max_diff,
              max_near_border);
  EXPECT_LT(p99, 0.005);      // metres, 0.01 GSD
  EXPECT_LT(max_diff, 0.05);  // 0.1 GSD
  EXPECT_GT(b.levels.back().times.intersect_s, 0);   // Embree did trace
  EXPECT_EQ(a.levels.back().times.intersect_s, 0);   // and was not needed
}

TEST(Refine, CancelledRunSaysSo) {
  const testing::Plane plane;
  const auto input = testing::MakePlaneInput(plane, testing::DefaultViews(),
                                             testing::PlaneMesh(plane, 40, 2.0, 1.0), 120);
  Progress progress;
  progress.is_cancelled = [] { return true; };
  try {
    Refine(input, SmallOptions(), progress);
    FAIL() << "expected cancellation";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kCancelled);
  }
}

TEST(Refine, FailsWithReasonWhenTheViewsDoNotConverge) {
  const testing::Plane plane;
  // Two views 1 degree apart: they do not constrain the height.
  const auto input = testing::MakePlaneInput(plane, {{0.5, 0}, {0.5, 180}},
                                             testing::PlaneMesh(plane, 40, 2.0, 1.0), 120);
  try {
    Refine(input, SmallOptions());
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find("no usable stereo pair"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("min_pair_angle_deg"), std::string::npos) << e.what();
  }
}

// In-track stereo as WorldView and Pléiades deliver it (15-35 degrees, one pair): refined
// from 1 m off to the plane. With the bias estimation on, the run succeeds but a uniform
// offset is not observable with one pair (it shifts the two views' projections as a
// relative bias would): the estimate absorbs it, and the surface stays where it was.
TEST(Refine, TwoViewStereoAtWideConvergenceRefines) {
  const testing::Plane plane;
  for (const double gamma : {15.0, 35.0}) {
    const auto input = testing::MakePlaneInput(plane, {{gamma / 2, 10}, {gamma / 2, 190}},
                                               testing::PlaneMesh(plane, 40, 1.0, 1.0));
    const RefineResult result = Refine(input, SmallOptions());
    ASSERT_EQ(result.pairs.size(), 1u);
    EXPECT_NEAR(result.pair_details[0].angle_deg, gamma, 0.5);
    const auto [mean, p95] = PlaneError(result.mesh, plane, 30);
    EXPECT_LT(mean, 0.15) << gamma;  // from 1 m (0.11-0.125: FollowedHitMapsDoNotDrift)
    EXPECT_LT(p95, 0.3) << gamma;

    RefineOptions with_bias = SmallOptions();
    with_bias.estimate_bias = true;
    const RefineResult biased = Refine(input, with_bias);
    ASSERT_EQ(biased.view_bias_px.size(), 2u);
    EXPECT_LT(PlaneError(biased.mesh, plane, 30).first, 1.1) << gamma;  // no worse
  }
}

// Between rasterizations a pixel's point follows its face along the pixel's ray
// (FollowHitMaps), so the surface a pair converges to does not depend on how often the hit
// maps are made anew, nor drift with more iterations. Moving the point with the face (at
// its barycentrics) put it off the ray: the plane below, from 1 m off under a 15 / 35
// degree pair, ended 0.084 / 0.087 m off after 15 iterations a level, 0.235 / 0.224 m after
// 30 and 0.222 / 0.242 m after 60, and 0.36 / 0.25 m with hit maps made every 4th
// iteration; made every iteration, 0.125 / 0.111 m (docs/benchmarks-history.md, session 33).
TEST(Refine, FollowedHitMapsDoNotDrift) {
  const testing::Plane plane;
  for (const double gamma : {15.0, 35.0}) {
    const auto input = testing::MakePlaneInput(plane, {{gamma / 2, 10}, {gamma / 2, 190}},
                                               testing::PlaneMesh(plane, 40, 1.0, 1.0));
    for (const auto& [iterations, every] : {std::pair{15, 1}, {15, 4}, {30, 2}}) {
      RefineOptions options = SmallOptions();
      options.iterations_per_level = iterations;
      options.hit_maps_every = every;
      const auto [mean, p95] = PlaneError(Refine(input, options).mesh, plane, 30);
      std::printf("%.0f degrees, %d iterations, hit maps every %d: mean %.4f m, p95 %.4f m\n",
                  gamma, iterations, every, mean, p95);
      EXPECT_LT(mean, 0.17) << gamma << " " << iterations << " " << every;
      EXPECT_LT(p95, 0.3) << gamma << " " << iterations << " " << every;
    }
  }
}

// The vertices' height sigma from the images' Fisher information (HeightConfidenceFromInformation)
// follows the pair's base-to-height ratio: on the same textured plane with the same noise,
// a 35-degree pair determines heights 2 tan(17.5°) / 2 tan(7.5°) = 2.39x better than a
// 15-degree one.
TEST(Refine, HeightSigmaFromTheImagesFollowsTheBaseToHeightRatio) {
  const testing::Plane plane;
  RefineOptions options = SmallOptions();
  options.levels = 0;
  options.iterations_per_level = 1;
  options.coarsest_iterations_factor = 1;
  options.height_sigma_gsd = 0.1;
  std::vector<double> median_sigma;
  for (const double gamma : {15.0, 35.0}) {
    auto input = testing::MakePlaneInput(plane, {{gamma / 2, 10}, {gamma / 2, 190}},
                                         testing::PlaneMesh(plane, 40, 1.0, 0.0));
    // The same noise in both views and both pairs (the renders are noise-free).
    uint32_t state = 12345;
    for (auto& view : input.views)
      for (float& px : view.image.pixels) {
        state = state * 1664525u + 1013904223u;
        px += 20.f * (float(state >> 8) / float(1 << 24) - 0.5f);
      }
    const RefineResult result = Refine(input, options);
    ASSERT_EQ(result.levels.size(), 1u);
    ASSERT_EQ(result.levels[0].height_sigma_gsd_q.size(), 3u);
    median_sigma.push_back(result.levels[0].height_sigma_gsd_q[1]);
    EXPECT_GT(median_sigma.back(), 0.0);
  }
  const double expected = std::tan(17.5 * M_PI / 180) / std::tan(7.5 * M_PI / 180);
  EXPECT_NEAR(median_sigma[0] / median_sigma[1], expected, 0.15 * expected);
}

// The initial surface's weight in the product of the images' height estimate (sigma_img² =
// noise / information) and the initial surface (prior sigma): 1 unseen, 1/2 where both
// are equally sure, -> 0 where the images pin the vertex.
TEST(InitialPriorWeights, IsTheInitialSurfacesShareOfTheTwoVariances) {
  const double noise = 4.0, prior = 0.5;  // prior variance 0.25
  const std::vector<float> w = InitialPriorWeights({0.0, 16.0, 4.0 * 16.0, 1e9}, noise, prior);
  ASSERT_EQ(w.size(), 4u);
  EXPECT_FLOAT_EQ(w[0], 1.0f);        // no pixel: the initial surface alone
  EXPECT_FLOAT_EQ(w[1], 0.5f);        // sigma_img² = 4 / 16 = 0.25 = prior²
  EXPECT_FLOAT_EQ(w[2], 0.2f);        // sigma_img² = 1/16: 0.0625 / (0.0625 + 0.25)
  EXPECT_LT(w[3], 1e-6f);
}

// Two views of `plane` whose texture is cut to 5% under strong uniform noise, the mesh
// started on the truth.
RefineInput WeakTextureUnderNoise(const testing::Plane& plane) {
  RefineInput input = testing::MakePlaneInput(plane, {{8, 10}, {8, 190}},
                                              testing::PlaneMesh(plane, 40, 1.0, 0.0));
  uint32_t state = 777;
  for (auto& view : input.views) {
    float mean = 0;
    for (float px : view.image.pixels) mean += px;
    mean /= float(view.image.pixels.size());
    for (float& px : view.image.pixels) {
      state = state * 1664525u + 1013904223u;
      px = mean + 0.05f * (px - mean) + 60.f * (float(state >> 8) / float(1 << 24) - 0.5f);
    }
  }
  return input;
}

// Mean distance of the refined WeakTextureUnderNoise plane to the truth, without the pull
// towards the start (initial_sigma_gsd 0) and with it (1.5).
std::array<double, 2> ErrorWithoutAndWithPull(RefineOptions options) {
  const testing::Plane plane;
  const RefineInput input = WeakTextureUnderNoise(plane);
  std::array<double, 2> error{};
  for (int k = 0; k < 2; ++k) {
    options.initial_sigma_gsd = k == 0 ? 0.0 : 1.5;
    error[k] = PlaneError(Refine(input, options).mesh, plane, 30).first;
  }
  return error;
}

// A weakly textured plane under strong noise, started on the truth: matching noise moves
// weakly constrained vertices; the pull towards the initial surface (initial_sigma_gsd)
// keeps them near it over many iterations, where without it they drift further.
TEST(Refine, InitialPriorKeepsWeaklyConstrainedVerticesNearTheStart) {
  RefineOptions options = SmallOptions();
  options.levels = 0;
  options.iterations_per_level = 30;  // 60 at the coarsest (factor 2)
  const std::array<double, 2> mean_error = ErrorWithoutAndWithPull(options);
  EXPECT_LT(mean_error[1], 0.7 * mean_error[0]) << "without: " << mean_error[0]
                                                 << " m, with: " << mean_error[1] << " m";
  EXPECT_LT(mean_error[1], 0.25);  // 0.5 GSD
}

// The same plane refined with a coarser level first: the finer level, too, keeps weakly
// constrained vertices near where it started them (the coarser level's result) instead of
// following its matching noise for 30 iterations. The finer level starts from that result
// in both runs (no restart from the initial surface, which here is the truth: whether a
// level restarts is a near tie of two ZNCCs under this noise, 0.0428 against 0.0418 +
// 0.001, which any change of the meshes tips; with the restart the test measured it, not
// the pull: 0.32 without the pull against 0.19 or 0.37 with it, session 38). Measured:
// 0.48 -> 0.37 m.
TEST(Refine, TheFinerLevelAlsoKeepsWeaklyConstrainedVerticesNearItsStart) {
  RefineOptions options = SmallOptions();
  options.levels = 1;
  options.iterations_per_level = 30;
  options.coarsest_iterations_factor = 1;  // 30 at each level
  options.restart_from_initial = false;
  const std::array<double, 2> mean_error = ErrorWithoutAndWithPull(options);
  EXPECT_LT(mean_error[1], 0.85 * mean_error[0]) << "without: " << mean_error[0]
                                                  << " m, with: " << mean_error[1] << " m";
}

// No pass follows a level's last step: level 0's height sigma comes from its last
// iterations (both directions of every pair: two iterations where the directions alternate,
// else the last with both). It matches a measurement of the finished surface
// (LevelHeightSigma, both directions) to within the last steps' change, for 2 and 4
// iterations (the two cases).
TEST(Refine, LevelZerosHeightSigmaIsTheFinishedSurfacesBothDirections) {
  const testing::Plane plane;
  const auto input = testing::MakePlaneInput(plane, testing::DefaultViews(),
                                             testing::PlaneMesh(plane, 40, 1.0, 0.3));
  const std::vector<PreparedView> views = PrepareViews(input, 0);
  for (int iterations : {2, 4}) {
    RefineOptions o = SmallOptions();
    o.levels = 0;
    o.iterations_per_level = iterations;
    const RefineResult r = Refine(input, o);
    ASSERT_EQ(r.mesh.height_sigma.size(), r.mesh.num_vertices());
    const std::vector<float> measured =
        LevelHeightSigma(input, views, r.pairs, o, r.gsd_m, 0, r.mesh);
    std::vector<double> ratio;
    for (size_t v = 0; v < measured.size(); ++v)
      if (std::isfinite(measured[v]) && std::isfinite(r.mesh.height_sigma[v]) && measured[v] > 0)
        ratio.push_back(r.mesh.height_sigma[v] / measured[v]);
    ASSERT_GT(ratio.size(), measured.size() / 2);
    std::nth_element(ratio.begin(), ratio.begin() + long(ratio.size() / 2), ratio.end());
    const double median = ratio[ratio.size() / 2];
    std::printf("%d iterations: median sigma ratio %.3f over %zu vertices\n", iterations, median,
                ratio.size());
    EXPECT_NEAR(median, 1.0, 0.1) << iterations;  // one direction only: sqrt(2) = 1.41
  }
}

}  // namespace
}  // namespace satmesh
