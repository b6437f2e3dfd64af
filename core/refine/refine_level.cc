#include "core/refine/refine_level.h"

#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/common/stage_time.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/edge_bias.h"
#include "core/refine/gradient_patch.h"
#include "core/refine/height_confidence.h"
#include "core/refine/hit_map_raster.h"
#include "core/refine/momentum.h"
#include "core/refine/photometric_pass.h"
#include "core/refine/plumb_walls.h"
#include "core/refine/sunlight.h"
#include "core/refine/thin_plate.h"
#include "core/refine/view_level.h"

namespace satmesh {
namespace {

// At every level (initial_sigma_gsd > 0), each iteration moves a vertex back towards where the
// level started it by this fraction of its offset times its InitialPriorWeights weight: a vertex
// the images do not see returns most of the way within ~20 iterations, and the low-frequency drift
// a single weakly textured pair produces is bounded instead of growing with the iterations
// (docs/benchmarks-history.md, session 13: stereo 0.5 m roofs 0.92x of the initial with 40
// iterations and no pull, 0.78x with it; 0.05-0.2 give the same). Below the coarsest level the
// start is the coarser level's result (or the initial surface after a restart), and only its height
// pulls: a vertex the finer images constrain weakly keeps the height the coarser level found
// instead of following their matching noise, while walls stay free to move sideways, which is what
// the finer level is for (docs/benchmarks-history.md, session 15: refined from the true surface,
// tri-stereo 0.3 m roofs drift to 0.107 m NMAD with the pull at the coarsest level only, 0.073 m
// with it at every level; from the DSM, 0.3 m roofs 0-4% better, facades within 0.3 points; pulling
// in 3D below the coarsest level cost 0.3-0.5 points of facades).
constexpr double kInitialPullPerIteration = 0.1;

// pairs_per_iteration: the iterations at a level's end that take every pair again (6 before
// session 33: the large jax job's levels 0.85x the time at 3, facades and F -0.3 points).
constexpr int kEveryPairAtTheEnd = 3;

// The level data of every view that takes part in a pair; slot[view] indexes it (-1: none).
std::vector<ViewLevel> MakeViewLevels(const RefineInput& input,
                                      const std::vector<PreparedView>& sources,
                                      const std::vector<std::pair<int, int>>& pairs,
                                      const TriangleMesh& mesh, int level, int grid_px,
                                      std::vector<int>* slot) {
  Eigen::Vector3d box_min, box_max;
  SurfaceBox(mesh, input.min_z, input.max_z, &box_min, &box_max);
  slot->assign(sources.size(), -1);
  std::vector<ViewLevel> views;
  for (const auto& [i, j] : pairs) {
    for (int v : {i, j}) {
      if ((*slot)[v] >= 0) continue;
      (*slot)[v] = int(views.size());
      views.push_back(MakeViewLevel(v, level, sources[v].pyramid[level], sources[v].rpc,
                                    input.frame, box_min, box_max, grid_px));
    }
  }
  return views;
}

// The images' suns when moving shadows are left out of the pairs (sunlit_pairs), else
// none; none too when no image says where its sun was.
std::vector<Eigen::Vector3f> SunsToMask(const RefineInput& input, const RefineOptions& options) {
  std::vector<Eigen::Vector3f> suns;
  if (!options.MatchesSunlitOnly(input.initial_is_mesh)) return suns;
  for (const RefineView& v : input.views) suns.push_back(SunDirection(v.acquisition));
  if (std::all_of(suns.begin(), suns.end(), [](const auto& d) { return d.squaredNorm() == 0; }))
    suns.clear();
  return suns;
}

// One photometric pass over both directions of every pair through the fixed `mesh`:
// the mean ZNCC, and each vertex's Fisher information when `information` is not null.
double MeasurePass(const RefineInput& input, const std::vector<PreparedView>& sources,
                   const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                   double level_gsd_m, int level, const TriangleMesh& mesh, bool rasterize,
                   std::vector<double>* information = nullptr, bool sunlit = false,
                   std::vector<std::vector<float>>* windows = nullptr) {
  std::vector<int> slot;
  std::vector<ViewLevel> views =
      MakeViewLevels(input, sources, pairs, mesh, level, options.virtual_camera_grid_px, &slot);
  const auto normals = FaceNormals(mesh);
  if (rasterize) {
    HitMapScratch raster;
    RasterizeHitMaps(mesh, &views, &raster, &normals);
  } else {
    const RayScene scene(mesh);
    for (auto& v : views) CastHitMap(scene, &v, &normals);
  }
  PhotometricOptions photo = PhotometricOptionsAt(options, level_gsd_m, MeanNoiseVariance(sources, level));
  photo.zncc.keep_windows = windows != nullptr;
  // sunlit: moving shadows left out as the level's iterations leave them out (sunlit_pairs),
  // so that a ZNCC measured here compares with theirs.
  const std::vector<Eigen::Vector3f> suns = sunlit ? SunsToMask(input, options) : std::vector<Eigen::Vector3f>{};
  if (!suns.empty()) {
    MarkSunlight(mesh, normals, suns, pairs, &views);
    photo.sunlit_only = true;
  }
  std::vector<PassScratch> scratch;
  if (information) information->assign(mesh.num_vertices(), 0.0);
  // (only the information is gathered, from the vertices' faces)
  const VertexAdjacency adjacency = information ? BuildVertexAdjacency(mesh) : VertexAdjacency{};
  return PhotometricPass(views, slot, pairs, mesh, normals, adjacency, photo, &scratch,
                         /*gradient=*/nullptr, /*seen=*/nullptr, /*one_direction=*/-1,
                         information, nullptr, windows);
}

}  // namespace

double LevelZncc(const RefineInput& input, const std::vector<PreparedView>& sources,
                 const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                 double level_gsd_m, int level, const TriangleMesh& mesh, bool rasterize) {
  return MeasurePass(input, sources, pairs, options, level_gsd_m, level, mesh, rasterize,
                     nullptr, /*sunlit=*/true);
}

std::vector<std::vector<float>> LevelWindowZncc(const RefineInput& input,
                                                const std::vector<PreparedView>& sources,
                                                const std::vector<std::pair<int, int>>& pairs,
                                                const RefineOptions& options, double level_gsd_m,
                                                int level, const TriangleMesh& mesh) {
  std::vector<std::vector<float>> windows;
  MeasurePass(input, sources, pairs, options, level_gsd_m, level, mesh, /*rasterize=*/false,
              nullptr, /*sunlit=*/true, &windows);
  return windows;
}

namespace {
// One rasterized pass: the mean ZNCC and the vertices' height sigma (LevelMeasure); sunlit as
// MeasurePass.
LevelMeasure MeasureWithSigma(const RefineInput& input, const std::vector<PreparedView>& sources,
                              const std::vector<std::pair<int, int>>& pairs,
                              const RefineOptions& options, double level_gsd_m, int level,
                              const TriangleMesh& mesh, bool sunlit) {
  std::vector<double> information;
  LevelMeasure out;
  out.mean_zncc = MeasurePass(input, sources, pairs, options, level_gsd_m, level, mesh,
                              /*rasterize=*/true, &information, sunlit);
  out.height_sigma = HeightSigmaFromInformation(information, MeanNoiseVariance(sources, level));
  return out;
}
}  // namespace

std::vector<float> LevelHeightSigma(const RefineInput& input,
                                    const std::vector<PreparedView>& sources,
                                    const std::vector<std::pair<int, int>>& pairs,
                                    const RefineOptions& options, double level_gsd_m, int level,
                                    const TriangleMesh& mesh) {
  return MeasureWithSigma(input, sources, pairs, options, level_gsd_m, level, mesh,
                          /*sunlit=*/false)
      .height_sigma;
}

LevelMeasure MeasureLevel(const RefineInput& input, const std::vector<PreparedView>& sources,
                          const std::vector<std::pair<int, int>>& pairs,
                          const RefineOptions& options, double level_gsd_m, int level,
                          const TriangleMesh& mesh) {
  return MeasureWithSigma(input, sources, pairs, options, level_gsd_m, level, mesh,
                          /*sunlit=*/true);
}

int PairGroups(const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options) {
  if (options.pairs_per_iteration <= 0) return 1;
  std::vector<int> views;
  for (const auto& [i, j] : pairs) views.push_back(i), views.push_back(j);
  std::sort(views.begin(), views.end());
  const int num_views = int(std::unique(views.begin(), views.end()) - views.begin());
  const int per_group = std::max(options.pairs_per_iteration, (num_views + 1) / 2);
  return std::max(1, (int(pairs.size()) + per_group - 1) / per_group);
}

namespace {
// The indices of the pairs in `group`. In list order, each pair joins the group (of those
// with room: ceil(pairs / groups) each) where its two views have the fewest pairs so far,
// then the smallest, then the first: each group spreads over the views. (Pair k in group
// k mod groups left a view out of a group: multi-date 0.5 m's 10 pairs of 6 views in 2
// groups, facades 0.4-1.0 points below every pair every iteration; balanced, within the
// runs' spread; docs/benchmarks-history.md, session 40.)
std::vector<size_t> PairGroupIndices(const std::vector<std::pair<int, int>>& pairs, int groups,
                                     int group) {
  const size_t room = (pairs.size() + size_t(groups) - 1) / size_t(groups);
  int num_views = 0;
  for (const auto& [i, j] : pairs) num_views = std::max({num_views, i + 1, j + 1});
  std::vector<std::vector<int>> uses(groups, std::vector<int>(num_views, 0));
  std::vector<size_t> size(groups, 0);
  std::vector<size_t> out;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto [i, j] = pairs[k];
    int best = -1;
    for (int g = 0; g < groups; ++g) {
      if (size[g] >= room) continue;
      if (best < 0) {
        best = g;
        continue;
      }
      const int a = uses[g][i] + uses[g][j], b = uses[best][i] + uses[best][j];
      if (a < b || (a == b && size[g] < size[best])) best = g;
    }
    ++size[best], ++uses[best][i], ++uses[best][j];
    if (best == group) out.push_back(k);
  }
  return out;
}
}  // namespace

std::vector<std::pair<int, int>> PairGroup(const std::vector<std::pair<int, int>>& pairs,
                                           int groups, int group) {
  std::vector<std::pair<int, int>> out;
  for (size_t k : PairGroupIndices(pairs, groups, group)) out.push_back(pairs[k]);
  return out;
}

std::vector<std::pair<int, int>> InitialCheckPairs(const std::vector<std::pair<int, int>>& pairs,
                                                   const RefineOptions& options) {
  return PairGroup(pairs, PairGroups(pairs, options), 0);
}

bool RefineLevel(const LevelContext& ctx, int level, double abandon_below, TriangleMesh* mesh,
                 LevelStats* stats_out) {
  const auto level_start = StageClock::now();
  const RefineOptions& opt = ctx.options;
  LevelStats& stats = *stats_out;
  stats = LevelStats{};
  stats.level = level;
  stats.gsd_m = ctx.gsd_m * std::ldexp(1.0, level);
  const double gsd = stats.gsd_m;

  std::vector<int> slot;
  std::vector<ViewLevel> views = MakeViewLevels(ctx.input, ctx.sources, ctx.pairs, *mesh, level,
                                                opt.virtual_camera_grid_px, &slot);
  const double noise_variance = MeanNoiseVariance(ctx.sources, level);
  PhotometricOptions photo = PhotometricOptionsAt(opt, gsd, noise_variance);
  // Moving shadows (sunlit_pairs): which suns light each pixel's point, by the level's
  // surface at its first iteration, kept for the level (the light changes little while the
  // surface moves by a fraction of a metre; marking costs ~3 s a time at 0.5 m).
  const std::vector<Eigen::Vector3f> suns = SunsToMask(ctx.input, opt);
  photo.sunlit_only = !suns.empty();

  std::optional<RayScene> scene;  // Embree, unless the hit maps are rasterized
  if (!opt.rasterize_hit_maps) scene.emplace(*mesh);
  HitMapScratch raster;
  std::vector<PassScratch> scratch;
  const VertexAdjacency adjacency = BuildVertexAdjacency(*mesh);
  // smooth_offsets: at full resolution, the thin-plate term of the offset from the level's
  // start, U²(V - V0) = U²(V) - U²(V0) (the umbrella operator is linear), so the start's
  // creases are kept. A coarser level's start is a coarse remesh of the model, whose
  // creases are already zigzag approximations that depend on the remesher's every choice:
  // there the surface itself is smoothed (else the subdivision between levels follows the
  // zigzags: 6% more or fewer faces from the same mesh in another CRS).
  // grid_start: the umbrella's weights (1 / edge length) from the level's start, fixed for
  // its iterations (the operator stays linear, as the offsets' smoothing needs).
  const std::vector<float> umbrella_weights =
      opt.grid_start > 0 ? InverseLengthWeights(mesh->vertices, adjacency)
                         : std::vector<float>{};
  const std::vector<Eigen::Vector3f> start_u2 =
      level == 0 && opt.SmoothsOffsets(ctx.input.initial_is_mesh)
          ? UmbrellaSquared(mesh->vertices, adjacency, &umbrella_weights)
          : std::vector<Eigen::Vector3f>{};
  const size_t nv = mesh->vertices.size();
  stats.num_vertices = int(nv);
  stats.num_faces = int(mesh->faces.size());
  std::vector<Eigen::Vector3d> gradient(nv);
  std::vector<int> seen(nv);
  // Per-vertex height confidence (HeightConfidenceFromInformation), from the level's first
  // iteration (both directions of every pair); empty: from the pairs' geometry.
  std::vector<double> information;
  std::vector<float> confidence;
  const bool data_confidence = opt.height_sigma_gsd > 0 && opt.min_height_confidence < 1;
  // Every level keeps weakly constrained vertices near where it started them
  // (InitialPriorWeights, kInitialPullPerIteration): the coarsest level near the initial
  // surface, finer ones at the heights of the coarser level's result (or of the initial
  // surface after a restart).
  const bool coarsest = level == opt.levels;
  const bool initial_prior = opt.initial_sigma_gsd > 0;
  const std::vector<Eigen::Vector3f> start = initial_prior ? mesh->vertices
                                                           : std::vector<Eigen::Vector3f>{};
  std::vector<float> prior_weight;
  if (data_confidence || initial_prior || level == 0) information.assign(nv, 0.0);
  const int iterations =
      coarsest ? int(std::lround(opt.coarsest_iterations_factor * opt.iterations_per_level))
               : opt.iterations_per_level;

  // pairs_per_iteration: the pairs fall into `groups`; a middle iteration takes one group,
  // in turn, and updates only its views' hit maps (made anew every hit_maps_every turns,
  // else followed). The last kEveryPairAtTheEnd iterations take every pair again: one
  // group's step is a noisier one, and the surface ends where all pairs agree (the jax set
  // at 300 m, 39 pairs in 3 groups, plain steps: roofs NMAD 0.058 m without, 0.054 m with 6,
  // as with every pair every iteration; docs/benchmarks-history.md, sessions 23 and 33).
  const int groups = PairGroups(ctx.pairs, opt);
  std::vector<std::pair<int, int>> group_pairs;
  std::vector<PairEnergy> first_energies;  // the first iteration's, per pair-direction
  std::vector<HitMapUpdate> update(views.size());
  std::vector<int> made_at(views.size(), 0);
  // A level's last iteration takes both directions of every pair where the pairs are one
  // group: with one direction last, where the level ends depends on which one (the count's
  // parity: stereo 0.3 m roofs 0.229-0.235 m after an even count, 0.222-0.223 after an odd
  // one; history, session 32). With more groups the last iterations' directions alternate
  // across the pairs, and both would cost 8% of the jax job's level 0 for the same result.
  const bool both_last = groups == 1;
  // No pass after the last step only to measure (it cost 12% of level 0's photometric
  // work on the large job, and a rasterization of every view): at level 0 the last
  // iterations, which take every pair, gather the Fisher information of the surface for
  // its height sigma, both directions of each pair (the last iteration where it takes
  // both, else the last two, which alternate). iterations 0: one pass that measures and
  // moves nothing.
  const bool measure_only = iterations == 0;
  const int passes = std::max(1, iterations);
  const int gathering =
      level == 0 ? (opt.alternate_directions && passes >= 3 && !both_last ? 2 : 1) : 0;
  const int information_from = passes - gathering;
  // MomentumStep: each vertex's last two moves (the level's first two steps carry nothing).
  std::vector<Eigen::Vector3f> last_move(opt.momentum > 0 ? nv : 0, Eigen::Vector3f::Zero());
  std::vector<Eigen::Vector3f> move_before(last_move.size(), Eigen::Vector3f::Zero());
  // wall_patch_rings (resolved by Refine): the patches of the level's start, whose faces
  // keep their facing while the walls move a fraction of a metre.
  const GradientPatches wall_patches =
      level == 0 && opt.wall_patch_rings > 0
          ? MakeWallPatches(*mesh, adjacency, opt.wall_patch_rings)
          : GradientPatches{};
  // roof_patch_rings: made once the first pass has measured which vertices the images
  // constrain weakly (prior_weight); none without the pull towards the start.
  GradientPatches roof_patches;
  // plumb_walls: the walls' tops at the level's start (with the pull to it; not measure-only).
  const PlumbLines plumb = level == 0 && initial_prior && !measure_only &&
                                   opt.HangsWallsPlumb(ctx.input.initial_is_mesh)
                               ? MakePlumbLines(*mesh, adjacency)
                               : PlumbLines{};
  if (!plumb.top.empty())
    spdlog::info("level 0: {} wall vertices hang from their walls' tops where the images "
                 "constrain them weakly", plumb.num_hung());

  for (int it = 0; it < passes; ++it) {
    ctx.progress.ThrowIfCancelled();
    const bool last = it == passes - 1;
    const bool final_information = it >= information_from;
    const bool grouped = groups > 1 && it > 0 && it < iterations - kEveryPairAtTheEnd;
    group_pairs = PairGroup(ctx.pairs, grouped ? groups : 1, grouped ? (it - 1) % groups : 0);
    // Iterations after the first take one direction per pair, alternating (from one turn
    // through the groups to the next where the pairs are grouped), but the last where the
    // pairs are one group or it alone gathers level 0's information.
    const bool half = opt.alternate_directions && it > 0 && !(last && (both_last || gathering == 1));
    const int turn = grouped ? (it - 1) / groups : it;
    const int one_direction = half ? turn % 2 : -1;
    // Only the views this iteration warps (each direction's first) follow or are made anew:
    // one only warped into is read for visibility, within 2 GSD, which its points a few
    // tenths of a GSD old answer (jax 300 m: hit maps 14.6 -> 12.1 s; history, session 33).
    std::fill(update.begin(), update.end(), HitMapUpdate::kKeep);
    for (const auto& [i, j] : PairDirections(group_pairs, one_direction))
      update[slot[i]] = HitMapUpdate::kFollow;
    for (size_t v = 0; v < views.size(); ++v) {
      if (update[v] == HitMapUpdate::kFollow &&
          (it == 0 || it - made_at[v] >= opt.hit_maps_every * (grouped ? groups : 1))) {
        update[v] = HitMapUpdate::kRasterize;
        made_at[v] = it;
      }
    }
    auto t0 = StageClock::now();
    const auto normals = FaceNormals(*mesh);
    if (!opt.rasterize_hit_maps) {  // made anew by Embree instead
      for (size_t v = 0; v < views.size(); ++v) {
        if (update[v] != HitMapUpdate::kRasterize) continue;
        stats.times.intersect_s += CastHitMap(*scene, &views[v], &normals);
        update[v] = HitMapUpdate::kKeep;
      }
    }
    UpdateHitMaps(*mesh, &views, &raster, &normals, update);
    if (!suns.empty() && it == 0) {
      const auto ts = StageClock::now();
      MarkSunlight(*mesh, normals, suns, ctx.pairs, &views);
      stats.times.sunlight_s += SecondsSince(ts);
    }
    stats.times.hit_maps_s += SecondsSince(t0);

    t0 = StageClock::now();
    std::fill(gradient.begin(), gradient.end(), Eigen::Vector3d::Zero());
    std::fill(seen.begin(), seen.end(), 0);
    if (it == information_from && it > 0) std::fill(information.begin(), information.end(), 0.0);
    const double zncc = PhotometricPass(
        views, slot, group_pairs, *mesh, normals, adjacency, photo, &scratch,
        measure_only ? nullptr : &gradient, measure_only ? nullptr : &seen, one_direction,
        (it == 0 && (data_confidence || initial_prior)) || final_information ? &information
                                                                             : nullptr,
        it == 0 && groups > 1 ? &first_energies : nullptr);
    if (it == 0 && data_confidence)
      confidence = HeightConfidenceFromInformation(information, noise_variance, gsd, opt, &stats);
    if (it == 0 && initial_prior) {
      prior_weight = InitialPriorWeights(information, noise_variance, opt.initial_sigma_gsd * gsd);
      if (level == 0 && opt.roof_patch_rings > 0 && !measure_only) {
        roof_patches = MakeRoofPatches(*mesh, adjacency, opt.roof_patch_rings, prior_weight);
        spdlog::info("level 0: {} of {} vertices are roof or ground the images constrain "
                     "weakly: they step with their planes' patches",
                     roof_patches.num_patches(), nv);
      }
    }
    stats.mean_zncc.push_back(zncc);
    stats.pair_directions += int(group_pairs.size()) * (half ? 1 : 2);
    stats.times.gradient_s += SecondsSince(t0);
    if (it == 0) {
      // Over the pairs the initial surface is measured on (InitialCheckPairs, group 0):
      // pair k's directions are 2k and 2k + 1.
      stats.check_zncc = zncc;
      if (groups > 1) {
        double sum = 0;
        long count = 0;
        for (size_t k : PairGroupIndices(ctx.pairs, groups, 0))
          for (size_t d : {2 * k, 2 * k + 1})
            sum += first_energies[d].sum_zncc, count += first_energies[d].num_windows;
        stats.check_zncc = count > 0 ? sum / double(count) : 0.0;
      }
      if (stats.check_zncc < abandon_below) return false;
    }
    // The finished surface's height sigma from the images (+inf: no image sees it).
    if (last && level == 0)
      mesh->height_sigma = HeightSigmaFromInformation(information, noise_variance);
    if (measure_only) break;

    t0 = StageClock::now();
    std::vector<Eigen::Vector3f> u2 = UmbrellaSquared(mesh->vertices, adjacency, &umbrella_weights);
    if (!start_u2.empty())
      for (size_t v = 0; v < nv; ++v) u2[v] -= start_u2[v];
    stats.times.smoothness_s += SecondsSince(t0);

    // Gradient step: photometric part in units of GSD², thin-plate homogenised by 1/GSD².
    t0 = StageClock::now();
    if (!wall_patches.normal.empty())
      PoolPatchGradients(wall_patches, &gradient, opt.hold_unseen ? &seen : nullptr);
    if (!roof_patches.normal.empty())
      PoolPatchGradients(roof_patches, &gradient, opt.hold_unseen ? &seen : nullptr);
    const double photo_scale = opt.step * opt.alpha * gsd * gsd;
    const double smooth_scale = opt.step * opt.beta;
    const double max_move = opt.max_step_gsd * gsd;
    const double directions_per_pair = (half ? 1.0 : 2.0) / (grouped ? groups : 1);
    const float* confidence_of = confidence.data();
    // plumb_walls: each hung vertex's offset outside its top's vertical, before any moves.
    const std::vector<float> plumb_offset = PlumbOffsets(plumb, mesh->vertices);
    // wall_beta_factor: the wall vertices (none looked for at 1, the default).
    const std::vector<char> on_wall =
        opt.wall_beta_factor < 1 ? WallVertices(*mesh) : std::vector<char>();
#pragma omp parallel for schedule(static)
    for (long v = 0; v < long(nv); ++v) {
      // plumb_walls (`hang`): across its wall a hung vertex is pulled to its start or to its
      // top's vertical, whichever lies further in (an arcade keeps its start: plumb_walls.h).
      const bool hung = !plumb_offset.empty() && plumb.top[v] >= 0 &&
                        !(opt.hold_boundary_xy && adjacency.is_boundary[v]);
      const double from_start =
          hung && coarsest ? double((mesh->vertices[v] - start[v]).dot(plumb.normal[v])) : 0.0;
      const double hang = hung ? kPlumbPullPerIteration * double(prior_weight[v]) *
                                     std::max(double(plumb_offset[v]), from_start)
                               : 0.0;
      if (opt.hold_unseen && seen[v] == 0) {  // no image constrains it: held, or hung plumb
        if (hung)  // nothing else moves it: at most max_move an iteration
          mesh->vertices[v] -= float(std::clamp(hang, -max_move, max_move)) * plumb.normal[v];
        continue;
      }
      Eigen::Vector3d g = gradient[v];
      if (opt.normalize_by_pair_count && seen[v] > 1) g /= double(seen[v]);
      const double confidence =
          data_confidence
              ? double(confidence_of[v])
              : HeightConfidence(seen[v] / directions_per_pair * ctx.mean_pair_information, opt);
      const double smooth = smooth_scale * (!on_wall.empty() && on_wall[v] ? opt.wall_beta_factor : 1.0) / confidence;
      Eigen::Vector3d move = -photo_scale * g - smooth * u2[v].cast<double>();
      if (initial_prior) {
        Eigen::Vector3d off = (mesh->vertices[v] - start[v]).cast<double>();
        if (!coarsest) off.x() = off.y() = 0;  // below the coarsest: heights only
        if (hung) {  // across its wall the hang pulls, not the start
          const Eigen::Vector3d h = plumb.normal[v].cast<double>();
          off -= off.dot(h) * h;
          move -= hang * h;
        }
        move -= kInitialPullPerIteration * double(prior_weight[v]) * off;
      }
      if (opt.hold_boundary_xy && adjacency.is_boundary[v]) move.x() = move.y() = 0;
      if (opt.momentum > 0)
        move = MomentumStep(move, AgreedMove(last_move[v], move_before[v]), opt.momentum);
      const double len = move.norm();
      if (len > max_move) move *= max_move / len;
      if (opt.momentum > 0) move_before[v] = last_move[v], last_move[v] = move.cast<float>();
      mesh->vertices[v] += move.cast<float>();
    }
    if (scene) scene->UpdateVertices(mesh->vertices);
    stats.times.update_s += SecondsSince(t0);
    ++stats.iterations;
    const double done = (opt.levels - level + double(it + 1) / passes);
    ctx.progress.Report(done / (opt.levels + 1), "level " + std::to_string(level));
  }
  stats.level_s = SecondsSince(level_start);
  spdlog::info("level {}: {} vertices, {} faces, GSD {:.2f} m, mean ZNCC {:.4f} -> {:.4f} ({:.1f} s)",
               level, stats.num_vertices, stats.num_faces, gsd, stats.mean_zncc.front(),
               stats.mean_zncc.back(), stats.level_s);
  return true;
}

}  // namespace satmesh
