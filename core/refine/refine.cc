#include "core/refine/refine.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/common/error.h"
#include "core/common/memory.h"
#include "core/common/stage_time.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/bias_estimation.h"
#include "core/refine/carry_displacement.h"
#include "core/refine/coarse_mesh.h"
#include "core/refine/edge_bias.h"
#include "core/refine/height_confidence.h"
#include "core/refine/level_start.h"
#include "core/refine/mesh_resolution.h"
#include "core/refine/pairs.h"
#include "core/refine/refine_level.h"
#include "core/refine/significance.h"
#include "core/refine/view_setup.h"

namespace satmesh {
namespace {

// A level keeps the previous level's result only if its mean ZNCC beats the initial
// surface's by more than this, about what meshing the same surface differently changes (a
// DSM's grid mesh vs its remeshed version: 0.0004-0.0007 on the Pléiades triplet). Within
// that, the two explain the images equally well and the initial surface, the user's data
// at full resolution, is kept (docs/benchmarks-history.md, session 7: on Pléiades the
// coarse levels of a narrow pair drift by 0.5 m where they tie with s2p's DSM).
constexpr double kKeepMargin = 0.001;
// A mesh start's extra coarser level (ResolveLevels, carried) is kept only where the
// full-resolution images leave the median vertex's height uncertain beyond this (GSD).
constexpr double kCarriedLevelSigmaGsd = 0.5;

// Once a level's result beats the initial surface by more than this, the finer levels
// no longer measure the initial surface (one photometric pass over a mesh with twice the
// level's faces, ~9% of a large tile's time): a chain that wins clearly keeps winning at
// the finer levels (synthetic scenes: 0.019-0.026 at level 1, then 0.037-0.071 at level
// 0; large with levels 3: 0.013, 0.008, 0.009; docs/benchmarks-history.md, session 8),
// while a DSM as sharp as the images ties with it (Pléiades: < 0.001).
constexpr double kSkipCheckMargin = 0.01;

void CheckInput(const RefineInput& input) {
  SATMESH_CHECK(input.views.size() >= 2, ErrorCode::kInvalidInput,
                "refine: need at least 2 views, got " + std::to_string(input.views.size()));
  for (const auto& v : input.views)
    SATMESH_CHECK(!v.image.empty(), ErrorCode::kInvalidInput, "refine: view '" + v.name + "' has no pixels");
  SATMESH_CHECK(!input.initial_mesh.faces.empty(), ErrorCode::kInvalidInput,
                "refine: the initial mesh has no faces");
  SATMESH_CHECK(input.max_z > input.min_z, ErrorCode::kInvalidInput,
                "refine: empty height range [min_z, max_z]");
}

// Step 2: the pairs, or an error that says why there is none.
PairSelection SelectPairsOrThrow(const RefineInput& input, const std::vector<PreparedView>& views,
                                 const PairOptions& options) {
  PairSelection selection = SelectViewPairs(input, views, options);
  SATMESH_CHECK(!selection.pairs.empty(), ErrorCode::kInvalidInput,
                "refine: no usable stereo pair among " + std::to_string(views.size()) +
                    " views: " + selection.refusal);
  for (const StereoPair& p : selection.pairs)
    spdlog::info("refine: pair {}-{} ({} / {}): {:.1f} deg, overlap {:.2f}, score {:.3f}", p.i,
                 p.j, input.views[p.i].name, input.views[p.j].name, p.angle_deg, p.overlap,
                 p.score);
  if (!selection.unpaired_views.empty())
    spdlog::warn("refine: {} usable view(s) have no partner within the angle and overlap "
                 "bounds; they are not used",
                 selection.unpaired_views.size());
  return selection;
}

// Step 3: per-view RPC bias shifts over the initial surface, through the selected pairs
// (connected where the views can be: one reference reaches every refined view). Changes
// the prepared views' RPCs.
void EstimateBiases(const RefineInput& input, const PairSelection& selection,
                    const RefineOptions& options, const Progress& progress,
                    std::vector<PreparedView>* views, RefineResult* result) {
  const auto t0 = StageClock::now();
  BiasOptions bias;
  bias.refine = options;
  const BiasEstimate estimate =
      EstimateViewBiases(input, *views, selection.IndexPairsBestFirst(), bias, progress);
  for (size_t v = 0; v < views->size(); ++v) {
    RpcModel& rpc = (*views)[v].rpc;
    rpc = rpc.WithBias(rpc.bias() + estimate.bias_col_row_px[v]);
  }
  result->view_bias_px = estimate.bias_col_row_px;
  result->bias_s = SecondsSince(t0);
}

// Step 4b, RefineOptions::crease_pass: level 0 run again from its result with the faces
// near its creases subdivided (FacesToSubdivide at flat_tolerance_gsd, as between levels,
// where a job without coarser levels gave its walls 2-pixel triangles only). On the DSM's
// grid of multi-date 0.5 m sets (3 seeds made after the choice): facades @0.5 m 46.2 / 41.2
// / 42.3 -> 49.9 / 44.4 / 45.6%, F 55.0 / 52.7 / 53.2 -> 56.5 / 53.8 / 54.6, roofs 0.258 /
// 0.267 / 0.220 -> 0.249 / 0.273 / 0.223 m; 50 iterations at 2 pixels instead: 47.7 / 42.6 /
// 43.5% (docs/benchmarks-history.md, session 26). It rasterizes three times the faces: 20 s
// a job instead of 10. One pair's 1-pixel triangles are its noise (stereo 0.5 m roofs 8%
// worse, the real Pléiades pairs' held-out ZNCC lower): by default where more than one pair
// was selected (tri-stereo 0.5 m s1 / s2 / s3 on the remesh: roofs 0.348 / 0.366 / 0.330 ->
// 0.332 / 0.345 / 0.328 m, facades +0.8 to +1.6 points; ResolveCreasePass). The pass
// continues level 0's result, it does not start from the initial surface: it takes
// iterations_per_level, not the coarsest level's coarsest_iterations_factor times that
// (multi-date 0.5 m s1 / s2 / s3 / seed 53, 40 -> 20 iterations: roofs -0.003 to +0.001 m,
// facades -0.1 to -0.5 points, under overhangs -0.1 to -0.6, F equal or +0.2, the job
// 0.8x the time; docs/benchmarks-history.md, session 39). After the adaptive start the
// creases have 1-pixel triangles already: level 0 runs again on them unsubdivided. Its walls
// hang again from the tops level 0 found (plumb_walls) and the pull starts from level 0's
// result: tri-stereo 0.5 m s1 / s2 (unseen walls hung at once in both), facades 56.8 / 57.9
// -> 60.2 / 62.0%, F 62.0 / 66.1 -> 63.8 / 68.2, roofs 0.276 / 0.242 -> 0.278 / 0.231 m,
// 1.3x the time; subdivided, +0.3 to +0.7 points of facades with 1.65x the faces
// (docs/benchmarks-history.md, session 47; before the hang, session 36, the pass gained less
// and cost roofs 2-3%, and did not follow the adaptive start).
void CreasePass(const LevelContext& level0, TriangleMesh* mesh, RefineResult* result) {
  RefineOptions continued = level0.options;
  continued.coarsest_iterations_factor = 1;
  const LevelContext ctx{level0.input,   continued,    level0.progress,
                         level0.sources, level0.pairs, level0.mean_pair_information,
                         level0.gsd_m};
  const double tolerance_m = ctx.options.flat_tolerance_gsd * ctx.gsd_m;
  const size_t faces_before = mesh->num_faces();
  if (result->adaptive_start) {
    spdlog::info("level 0 again: the adaptive start's creases are fine already ({} faces)",
                 faces_before);
  } else {
    const size_t subdivided = SubdivideNearCreases(tolerance_m, mesh);
    spdlog::info("level 0, creases: {} of {} faces subdivided where a vertex is off its "
                 "neighbours' plane by more than {:.2f} m ({} faces)",
                 subdivided, faces_before, tolerance_m, mesh->num_faces());
  }
  LevelStats stats;
  ReturnFreedMemory();  // level 0's workspaces: the pass's peak is its own
  RefineLevel(ctx, 0, std::numeric_limits<double>::quiet_NaN(), mesh, &stats);
  stats.crease_pass = true;
  result->levels.push_back(std::move(stats));
}

// crease_pass -1: on for a DSM start without coarser levels and with more than one pair
// (after the adaptive start, level_start.cc, without subdividing: CreasePass).
int ResolveCreasePass(const RefineOptions& options, bool initial_is_mesh, size_t num_pairs) {
  if (options.crease_pass >= 0) return options.crease_pass;
  return options.levels == 0 && !initial_is_mesh && num_pairs > 1 ? 1 : 0;
}

// Step 4: coarse to fine. Below the coarsest level, the previous level's result
// (subdivided) competes with the initial surface: a DSM as sharp as the images loses
// detail on the coarse levels that their iterations do not win back
// (docs/benchmarks-history.md, Pléiades run 5). A carried start (carry_coarse_levels: a
// mesh start) continues instead from the initial surface remeshed for the level and moved
// as the coarser level moved it (CarryDisplacement): the coarse level corrects the start at
// its scale, the start keeps its walls (stereo 0.5 m, the truth moved 1 m by smooth noise:
// roofs 0.430 -> 0.323 m, the DSM start 0.350 m; docs/benchmarks-history.md, session 21).
void CoarseToFine(const RefineInput& input, const RefineOptions& options,
                  const Progress& progress, const std::vector<PreparedView>& views,
                  RefineResult* result, std::optional<TriangleMesh> level0_start,
                  double level0_initial_zncc) {
  // level0_start: LevelStartMesh at level 0, made already. level0_initial_zncc: the initial
  // surface's mean ZNCC at level 0 over the check's pairs, measured already (NaN: not).
  TriangleMesh mesh =
      options.levels == 0 && level0_start
          ? std::move(*level0_start)
          : LevelStartMesh(input, options, views, result->pairs, result->gsd_m, progress, options.levels);
  // With a crease pass the levels report (levels + 1) / (levels + 2) of the progress.
  const int parts = options.levels + 1 + (options.crease_pass > 0 ? 1 : 0);
  const auto part_of = [&progress, parts, levels = options.levels](int offset) {
    return Progress{[&progress, parts, levels, offset](double f, const std::string& stage) {
                      progress.Report(((levels + 1) * f + offset) / parts, stage);
                    },
                    progress.is_cancelled};
  };
  const Progress level_progress = part_of(0);
  const LevelContext ctx{input,
                         options,
                         level_progress,
                         views,
                         result->pairs,
                         MeanRelativePairInformation(result->pair_details, options),
                         result->gsd_m};
  bool check_initial = options.restart_from_initial;
  const std::vector<std::pair<int, int>> check_pairs = InitialCheckPairs(result->pairs, options);
  const bool carry = options.CarriesCoarseLevels(input.initial_is_mesh);
  TriangleMesh reference;  // carry: the level's mesh before its iterations
  for (int level = options.levels; level >= 0; --level) {
    const auto level_start = StageClock::now();
    double initial_zncc = std::numeric_limits<double>::quiet_NaN(), check_s = 0;
    TriangleMesh initial;
    if (level < options.levels && carry) {
      TriangleMesh fine =
          level == 0 && level0_start
              ? std::move(*level0_start)
              : LevelStartMesh(input, options, views, result->pairs, result->gsd_m, progress, level);
      mesh = CarryDisplacement(reference, mesh, fine);
      reference = std::move(fine);
      spdlog::info("level {}: the initial surface remeshed ({} faces), moved as level {} moved it",
                   level, mesh.num_faces(), level + 1);
    } else if (level < options.levels) {
      const size_t faces_before = mesh.num_faces();
      const size_t subdivided = SubdivideNearCreases(
          options.flat_tolerance_gsd * result->gsd_m * std::ldexp(1.0, level + 1), &mesh);
      if (options.flat_tolerance_gsd > 0)
        spdlog::info("level {}: {} of {} faces subdivided ({} -> {} faces)", level, subdivided,
                     faces_before, faces_before, mesh.num_faces());
    } else if (carry) {
      reference = mesh;
    }
    if (level < options.levels) {
      if (check_initial && level == 0 && !std::isnan(level0_initial_zncc)) {
        // measured by ChooseCoarseStart on the level-0 grid, which a restart starts from
        // (RemeshForLevel): `initial` is not needed
        initial_zncc = level0_initial_zncc;
      } else if (check_initial) {
        const auto t0 = StageClock::now();
        initial = InitialSurfaceAt(input, options, result->gsd_m, level);
        initial_zncc = LevelZncc(input, views, check_pairs, options,
                                 result->gsd_m * std::ldexp(1.0, level), level, initial,
                                 options.rasterize_hit_maps);
        check_s = SecondsSince(t0);
      }
    }
    LevelStats stats;
    bool restarted = false;
    ReturnFreedMemory();  // the start's remeshing and tests: the level's peak is its own
    if (!RefineLevel(ctx, level, initial_zncc + kKeepMargin, &mesh, &stats)) {
      spdlog::info("level {}: the previous level's mean ZNCC {:.4f} does not beat the "
                   "initial surface's {:.4f} by {} (over {} of {} pairs); restarting from the "
                   "initial surface",
                   level, stats.check_zncc, initial_zncc, kKeepMargin, check_pairs.size(),
                   result->pairs.size());
      if (carry) mesh = reference;  // the initial surface remeshed for the level, unmoved
      else mesh = RemeshForLevel(input, std::move(initial), options, result->gsd_m, level, progress);
      RefineLevel(ctx, level, std::numeric_limits<double>::quiet_NaN(), &mesh, &stats);
      restarted = true;
    } else if (!std::isnan(initial_zncc)) {
      check_initial = stats.check_zncc <= initial_zncc + kSkipCheckMargin;
      spdlog::info("level {}: kept the previous level's result (mean ZNCC {:.4f}, the initial "
                   "surface's {:.4f} over {} of {} pairs, {:.1f} s to measure){}",
                   level, stats.check_zncc, initial_zncc, check_pairs.size(), result->pairs.size(),
                   check_s,
                   check_initial ? "" : "; finer levels do not measure it again");
    }
    stats.initial_zncc = initial_zncc;
    stats.restarted = restarted;
    stats.initial_check_s = check_s;
    stats.level_s = SecondsSince(level_start);
    result->levels.push_back(std::move(stats));
  }
  if (options.crease_pass > 0) {
    const Progress crease_progress = part_of(1);
    CreasePass({input, options, crease_progress, views, result->pairs, ctx.mean_pair_information,
                result->gsd_m},
               &mesh, result);
  }
  result->mesh = std::move(mesh);
}

// Step 5: KeepSignificantChanges with keep_initial_sigmas (-1: 2 for a mesh start or a
// trusted DSM start, off for a DSM start), after registering the result to the initial
// surface (RegisterToInitial).
// Refined from the true surface of a multi-date 0.3 m scene, roofs drift by the matching
// noise to 0.073 m NMAD without it, 0.012 m with it; from a stereo DSM it would undo real
// corrections the images make only as a whole (stereo 0.5 m roofs 0.79x -> 0.90x of the
// initial): docs/benchmarks-history.md, session 16. The registration takes off what the
// block's datum leaves (SurfaceDatum finds it to 0.04-0.07 m; minimum corrections put a
// multi-date 0.5 m block 0.26 m off the true mesh, and the refinement followed: session 17).
// Tested per vertex only, a start that is off smoothly (the truth moved 1 m by smooth noise)
// kept its error where the images correct it only as a whole (multi-date 0.5 m roofs 0.211
// / 0.236 m, the DSM start 0.211 / 0.227 m): the pooled tests first (keep_initial_scales)
// give 0.192 / 0.202 m, a true start 0.045 / 0.038 m (was 0.035 / 0.025): session 20.
void KeepInitialWithinNoise(const RefineInput& input, const RefineOptions& options,
                            RefineResult* result) {
  const double k = options.KeepInitialSigmas(input.initial_is_mesh);
  const bool registers = options.RegistersToInitial(input.initial_is_mesh);
  if (!(k > 0 || registers) || result->mesh.height_sigma.size() != result->mesh.num_vertices())
    return;
  // Offsets beyond 10 GSDs are changes whatever the noise (and beyond the reach looked at).
  SignificanceOptions significance;
  significance.k = k > 0 ? k : 0.0;
  significance.max_offset_m = 10 * result->gsd_m;
  significance.hold_boundary_xy = options.hold_boundary_xy;
  significance.register_to_initial = registers;
  significance.scales = options.keep_initial_scales;
  significance.gsd_m = result->gsd_m;
  significance.floor_gsd = options.keep_initial_floor_gsd;
  const SignificanceStats stats = KeepSignificantChanges(input.initial_mesh, significance, &result->mesh);
  result->kept_initial_share = 1 - stats.mean_gain;
  result->registration_m = stats.registration_m;
  if (registers)
    spdlog::info("refine: registered to the initial surface by ({:+.3f}, {:+.3f}, {:+.3f}) m",
                 -stats.registration_m.x(), -stats.registration_m.y(), -stats.registration_m.z());
  if (k > 0)
    spdlog::info("refine: the initial surface kept where the images do not contradict it beyond "
                 "{} sigmas: {:.0f}% of the offsets of {} vertices undone ({:.0f}% kept as "
                 "coherent over {} scale(s))",
                 k, 100 * (1 - stats.mean_gain), stats.vertices, 100 * stats.pooled_share,
                 options.keep_initial_scales);
}

}  // namespace

double MeasureMeanZncc(const RefineInput& input, const TriangleMesh& mesh,
                       const std::vector<std::pair<int, int>>& pairs, int level,
                       const RefineOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "refine options: " + problem);
  const std::vector<PreparedView> views = PrepareViews(input, level);
  const double gsd = views[pairs.front().first].gsd_m * std::ldexp(1.0, level);
  return LevelZncc(input, views, pairs, options, gsd, level, mesh, /*rasterize=*/false);
}

RefineResult Refine(const RefineInput& input, const RefineOptions& user_options,
                    const Progress& progress) {
  const std::string problem = user_options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "refine options: " + problem);
  CheckInput(input);
  const auto start = StageClock::now();
  RefineResult result;

  // 1. Levels from the GSD; normalisation, pyramids (deep enough for the bias search too),
  //    pair candidates.
  double gsd_sum = 0;
  for (const auto& v : input.views) gsd_sum += GroundSamplingDistance(v.rpc, input.frame);
  result.gsd_m = gsd_sum / double(input.views.size());
  RefineOptions options = user_options;
  options.levels = ResolveLevels(user_options, result.gsd_m, input.initial_cell_m, input.initial_is_mesh);
  if (user_options.levels < 0)
    spdlog::info("refine: {} coarser level(s): GSD {:.2f} m, initial surface cell {:.2f} m, "
                 "coarse edge {:.2f} m",
                 options.levels, result.gsd_m, input.initial_cell_m, LevelEdge(options, result.gsd_m, options.levels));
  std::vector<PreparedView> views =
      PrepareViews(input, std::max(options.levels, options.estimate_bias ? BiasOptions().coarse_level : 0));
  spdlog::info("refine: images' noise {:.4f} (std of the normalised full-resolution images, "
               "mean over views): ZNCC variance floor {:.2e} at level 0",
               std::sqrt(MeanNoiseVariance(views, 0)),
               PhotometricOptionsAt(options, result.gsd_m, MeanNoiseVariance(views, 0)).zncc.variance_floor);
  progress.ThrowIfCancelled();

  // 2. Pairs.
  const PairSelection selection = SelectPairsOrThrow(input, views, options.pairs);
  result.pairs = selection.IndexPairs();
  result.pair_details = selection.pairs;
  result.candidate_pairs = selection.num_candidates;
  spdlog::info("refine: {} views, {} pairs of {} candidates, GSD {:.3f} m", input.views.size(),
               result.pairs.size(), selection.num_candidates, result.gsd_m);

  // 3. Per-view RPC biases.
  if (options.estimate_bias) EstimateBiases(input, selection, options, progress, &views, &result);

  // The refinement's ZNCC window from the pairs (ResolveZnccWindowRadius), after the bias
  // estimation: that keeps the measurement's 5x5, as a tiled job's (job.cc) and `satmesh bias`.
  options.zncc_window_radius = ResolveZnccWindowRadius(options, result.pairs.size());
  if (user_options.zncc_window_radius < 0 && result.pairs.size() == 1)
    spdlog::info("refine: one pair: ZNCC windows of {0}x{0} pixels",
                 2 * options.zncc_window_radius + 1);
  options.wall_patch_rings = ResolveWallPatchRings(options, result.pairs.size());
  if (user_options.wall_patch_rings < 0 && options.wall_patch_rings > 0)
    spdlog::info("refine: one pair: walls move as patches of {} rings at level 0",
                 options.wall_patch_rings);

  // 4. Coarse to fine. The coarser level a carried start gets beyond a DSM start's
  //    (ResolveLevels) is dropped again where the full-resolution images determine the
  //    median vertex's height to within kCarriedLevelSigmaGsd (a multi-date set): level 0
  //    alone corrects the start there, and the coarse level's windows lifted the ground of
  //    courtyards and narrow streets (multi-date 0.5 m s1, perturbed: F 76.4 -> 72.9;
  //    docs/benchmarks-history.md, session 21), while a stereo or tri-stereo pass (1.5-3.7
  //    GSD) corrects a smooth error only with it.
  std::optional<TriangleMesh> level0_start;
  double level0_initial_zncc = std::numeric_limits<double>::quiet_NaN();
  options.grid_start = ChooseCoarseStart(input, options, views, result.pairs, result.gsd_m,
                                         &level0_start, &level0_initial_zncc);
  result.grid_start = options.grid_start;
  if (user_options.levels < 0 && options.levels == 1 &&
      options.CarriesCoarseLevels(input.initial_is_mesh) &&
      ResolveLevels(user_options, result.gsd_m, input.initial_cell_m, false) == 0) {
    double median_sigma_m = 0;
    level0_start =
        LevelStartMesh(input, options, views, result.pairs, result.gsd_m, progress, 0, &median_sigma_m);
    if (median_sigma_m <= kCarriedLevelSigmaGsd * result.gsd_m) {
      options.levels = 0;
      spdlog::info("refine: no coarser level after all: the images determine the median "
                   "vertex's height to {:.2f} m (within {} GSD)",
                   median_sigma_m, kCarriedLevelSigmaGsd);
    }
  }
  options.flat_edge_px = ResolveFlatEdge(options, input.initial_is_mesh, result.pairs.size());
  bool adaptive_start = false;
  if (options.levels == 0 && !level0_start)
    level0_start = LevelStartMesh(input, options, views, result.pairs, result.gsd_m, progress, 0,
                                  nullptr, &adaptive_start);
  result.adaptive_start = adaptive_start;
  options.crease_pass = ResolveCreasePass(options, input.initial_is_mesh, result.pairs.size());
  CoarseToFine(input, options, progress, views, &result, std::move(level0_start),
               level0_initial_zncc);

  // 4c. The photometric term's outward bias at occluding edges taken off (edge_bias.h).
  const double deflate_m = options.OccludingEdgeBiasPx(input.initial_is_mesh) * result.gsd_m;
  const size_t deflated = DeflateOccludingEdges(deflate_m, &result.mesh).moved;
  if (deflated > 0) spdlog::info("refine: {} wall vertices moved {:.2f} m inward", deflated, deflate_m);

  // 5. The initial surface kept where the images do not contradict it beyond their noise.
  KeepInitialWithinNoise(input, options, &result);
  result.total_s = SecondsSince(start);
  progress.Report(1.0, "done");
  return result;
}

}  // namespace satmesh
