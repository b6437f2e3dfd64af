#include "core/refine/refine.h"

#include <Eigen/LU>
#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "core/common/error.h"
#include "core/common/stage_time.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/bias_estimation.h"
#include "core/refine/coarse_mesh.h"
#include "core/refine/height_confidence.h"
#include "core/refine/hit_map_raster.h"
#include "core/refine/mesh_resolution.h"
#include "core/refine/pairs.h"
#include "core/refine/photometric_gradient.h"
#include "core/refine/significance.h"
#include "core/refine/thin_plate.h"
#include "core/refine/view_level.h"
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

// Once a level's result beats the initial surface by more than this, the finer levels
// no longer measure the initial surface (one photometric pass over a mesh with twice the
// level's faces, ~9% of a large tile's time): a chain that wins clearly keeps winning at
// the finer levels (synthetic scenes: 0.019-0.026 at level 1, then 0.037-0.071 at level
// 0; large with levels 3: 0.013, 0.008, 0.009; docs/benchmarks-history.md, session 8),
// while a DSM as sharp as the images ties with it (Pléiades: < 0.001).
constexpr double kSkipCheckMargin = 0.01;

// At every level (initial_sigma_gsd > 0), each iteration moves a vertex back towards where
// the level started it by this fraction of its offset times its InitialPriorWeights weight:
// a vertex the images do not see returns most of the way within ~20 iterations, and the
// low-frequency drift a single weakly textured pair produces is bounded instead of
// growing with the iterations (docs/benchmarks-history.md, session 13: stereo 0.5 m roofs
// 0.92x of the initial with 40 iterations and no pull, 0.78x with it; 0.05-0.2 give the
// same). Below the coarsest level the start is the coarser level's result (or the initial
// surface after a restart), and only its height pulls: a vertex the finer images constrain
// weakly keeps the height the coarser level found instead of following their matching
// noise, while walls stay free to move sideways, which is what the finer level is for
// (docs/benchmarks-history.md, session 15: refined from the true surface, tri-stereo 0.3 m
// roofs drift to 0.107 m NMAD with the pull at the coarsest level only, 0.073 m with it at
// every level; from the DSM, 0.3 m roofs 0-4% better, facades within 0.3 points; pulling
// in 3D below the coarsest level cost 0.3-0.5 points of facades).
constexpr double kInitialPullPerIteration = 0.1;


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

struct LevelContext {
  const RefineInput& input;
  const RefineOptions& options;
  const Progress& progress;
  const std::vector<PreparedView>& sources;
  std::vector<std::pair<int, int>>& pairs;
  double mean_pair_information;  // MeanRelativePairInformation of the selected pairs
  double gsd_m;
};

// One thread's buffers of the photometric pass, kept across iterations: they are tens
// of MB a thread at level 0, and fresh ones cost page faults and zeroing every pass.
struct PassScratch {
  GradientAccumulator accumulator;
  PairWorkspace workspace;
};

// Mean ZNCC over all pair-directions; fills the gradient and per-vertex pair counts.
// Pair-directions run in parallel (one per thread, gathered per face by each thread's
// accumulator, scattered to the vertices once at the end). The views' hit maps, with
// their ray cosines, must be current for the mesh and its face normals.
double PhotometricPass(std::vector<ViewLevel>& views, const std::vector<int>& slot,
                       const std::vector<std::pair<int, int>>& pairs, const TriangleMesh& mesh,
                       const std::vector<Eigen::Vector3f>& normals,
                       const PhotometricOptions& options, std::vector<PassScratch>* scratch,
                       std::vector<Eigen::Vector3d>* gradient, std::vector<int>* seen,
                       int one_direction = -1, std::vector<double>* information = nullptr) {
  // one_direction >= 0: pair k only as (i, j) if (one_direction + k) is even, else (j, i).
  std::vector<std::pair<int, int>> directions;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto [i, j] = pairs[k];
    if (one_direction < 0) directions.insert(directions.end(), {{i, j}, {j, i}});
    else if ((one_direction + k) % 2 == 0) directions.push_back({i, j});
    else directions.push_back({j, i});
  }
  const bool accumulate = gradient || seen || information;
  double sum = 0;
  long count = 0;
  if (scratch->size() < size_t(omp_get_max_threads())) scratch->resize(omp_get_max_threads());
#pragma omp parallel
  {
    PassScratch& own = (*scratch)[omp_get_thread_num()];
    GradientAccumulator& accumulator = own.accumulator;
    if (accumulate) accumulator.Reset(mesh, information != nullptr);
    PairWorkspace& workspace = own.workspace;
#pragma omp for schedule(dynamic, 1) reduction(+ : sum, count)
    for (size_t d = 0; d < directions.size(); ++d) {
      const auto [a, b] = directions[d];
      const PairEnergy e =
          AccumulatePairGradient(views[slot[a]], views[slot[b]], normals, options,
                                 accumulate ? &accumulator : nullptr, &workspace);
      sum += e.sum_zncc;
      count += e.num_windows;
    }
    if (accumulate) {
#pragma omp critical
      accumulator.AddTo(normals, gradient, seen, information);
    }
  }
  return count > 0 ? sum / count : 0.0;
}

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

// Mean ZNCC of `mesh` over `pairs` at `level`, without changing anything; hit maps
// rasterized or cast with Embree.
double LevelZncc(const RefineInput& input, const std::vector<PreparedView>& sources,
                 const std::vector<std::pair<int, int>>& pairs, const RefineOptions& options,
                 double level_gsd_m, int level, const TriangleMesh& mesh, bool rasterize) {
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
  std::vector<PassScratch> scratch;
  return PhotometricPass(views, slot, pairs, mesh, normals,
                         PhotometricOptionsAt(options, level_gsd_m, MeanNoiseVariance(sources, level)),
                         &scratch, nullptr, nullptr);
}

// The iterations of one level. Returns false, before changing the mesh, if the mean ZNCC
// of the level's first iteration is below `abandon_below` (NaN: never).
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
  const PhotometricOptions photo = PhotometricOptionsAt(opt, gsd, noise_variance);

  std::optional<RayScene> scene;  // Embree, unless the hit maps are rasterized
  if (!opt.rasterize_hit_maps) scene.emplace(*mesh);
  HitMapScratch raster;
  std::vector<PassScratch> scratch;
  const VertexAdjacency adjacency = BuildVertexAdjacency(*mesh);
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

  for (int it = 0; it <= iterations; ++it) {
    ctx.progress.ThrowIfCancelled();
    const bool last = it == iterations;
    auto t0 = StageClock::now();
    const auto normals = FaceNormals(*mesh);
    if (it > 0 && !last && it % opt.hit_maps_every != 0) {
      FollowHitMaps(*mesh, &views, &raster, &normals);  // faces kept, points moved with them
    } else if (opt.rasterize_hit_maps) {
      RasterizeHitMaps(*mesh, &views, &raster, &normals);
    } else {
      for (auto& v : views) {
        stats.times.intersect_s += CastHitMap(*scene, &v, &normals);
      }
    }
    stats.times.hit_maps_s += SecondsSince(t0);

    t0 = StageClock::now();
    std::fill(gradient.begin(), gradient.end(), Eigen::Vector3d::Zero());
    std::fill(seen.begin(), seen.end(), 0);
    if (last) std::fill(information.begin(), information.end(), 0.0);
    // Iterations between the first and the last take one direction per pair, alternating.
    const bool half = opt.alternate_directions && it > 0 && !last;
    const double zncc = PhotometricPass(views, slot, ctx.pairs, *mesh, normals, photo, &scratch,
                                        last ? nullptr : &gradient, last ? nullptr : &seen,
                                        half ? it % 2 : -1,
                                        (it == 0 && (data_confidence || initial_prior)) ||
                                                (last && level == 0)
                                            ? &information
                                            : nullptr);
    if (it == 0 && data_confidence)
      confidence = HeightConfidenceFromInformation(information, noise_variance, gsd, opt, &stats);
    if (it == 0 && initial_prior)
      prior_weight = InitialPriorWeights(information, noise_variance, opt.initial_sigma_gsd * gsd);
    stats.mean_zncc.push_back(zncc);
    stats.times.gradient_s += SecondsSince(t0);
    if (it == 0 && zncc < abandon_below) return false;
    if (last) {
      // The finished surface's height sigma from the images (+inf: no image sees it).
      if (level == 0) mesh->height_sigma = HeightSigmaFromInformation(information, noise_variance);
      break;
    }

    t0 = StageClock::now();
    const auto u2 = UmbrellaSquared(mesh->vertices, adjacency);
    stats.times.smoothness_s += SecondsSince(t0);

    // Gradient step: photometric part in units of GSD², thin-plate homogenised by 1/GSD².
    t0 = StageClock::now();
    const double photo_scale = opt.step * opt.alpha * gsd * gsd;
    const double smooth_scale = opt.step * opt.beta;
    const double max_move = opt.max_step_gsd * gsd;
    const double directions_per_pair = half ? 1.0 : 2.0;
    const float* confidence_of = confidence.data();
#pragma omp parallel for schedule(static)
    for (long v = 0; v < long(nv); ++v) {
      if (opt.hold_unseen && seen[v] == 0) continue;  // no image constrains it
      Eigen::Vector3d g = gradient[v];
      if (opt.normalize_by_pair_count && seen[v] > 1) g /= double(seen[v]);
      const double confidence =
          data_confidence
              ? double(confidence_of[v])
              : HeightConfidence(seen[v] / directions_per_pair * ctx.mean_pair_information, opt);
      Eigen::Vector3d move = -photo_scale * g - smooth_scale / confidence * u2[v].cast<double>();
      if (initial_prior) {
        Eigen::Vector3d off = (mesh->vertices[v] - start[v]).cast<double>();
        if (!coarsest) off.x() = off.y() = 0;  // below the coarsest: heights only
        move -= kInitialPullPerIteration * double(prior_weight[v]) * off;
      }
      if (opt.hold_boundary_xy && adjacency.is_boundary[v]) move.x() = move.y() = 0;
      const double len = move.norm();
      if (len > max_move) move *= max_move / len;
      mesh->vertices[v] += move.cast<float>();
    }
    if (scene) scene->UpdateVertices(mesh->vertices);
    stats.times.update_s += SecondsSince(t0);
    ++stats.iterations;
    const double done = (opt.levels - level + double(it + 1) / (iterations + 1));
    ctx.progress.Report(done / (opt.levels + 1), "level " + std::to_string(level));
  }
  stats.level_s = SecondsSince(level_start);
  spdlog::info("level {}: {} vertices, {} faces, GSD {:.2f} m, mean ZNCC {:.4f} -> {:.4f} ({:.1f} s)",
               level, stats.num_vertices, stats.num_faces, gsd, stats.mean_zncc.front(),
               stats.mean_zncc.back(), stats.level_s);
  return true;
}

// Triangle edge of `level`, metres: coarse_edge_px level pixels.
double LevelEdge(const RefineOptions& options, double gsd_m, int level) {
  return options.coarse_edge_px * gsd_m * std::ldexp(1.0, level);
}

// `mesh` remeshed isotropically to the triangle edge of `level`, unless
// options.remesh_coarse is off.
TriangleMesh RemeshForLevel(TriangleMesh mesh, const RefineOptions& options, double gsd_m,
                            int level, const Progress& progress) {
  if (!options.remesh_coarse) return mesh;
  CoarseMeshOptions coarse;
  coarse.target_edge_m = LevelEdge(options, gsd_m, level);
  return RemeshIsotropic(mesh, coarse, progress);
}

// The initial surface meshed for `level` (before remeshing): what a level below the
// coarsest measures and, if it wins, restarts from.
TriangleMesh InitialSurfaceAt(const RefineInput& input, const RefineOptions& options,
                              double gsd_m, int level) {
  if (!input.initial_for_edge) return input.initial_mesh;
  return input.initial_for_edge(LevelEdge(options, gsd_m, level));
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

// Step 4: coarse to fine. Below the coarsest level, the previous level's result
// (subdivided) competes with the initial surface: a DSM as sharp as the images loses
// detail on the coarse levels that their iterations do not win back
// (docs/benchmarks-history.md, Pléiades run 5).
void CoarseToFine(const RefineInput& input, const RefineOptions& options,
                  const Progress& progress, const std::vector<PreparedView>& views,
                  RefineResult* result) {
  TriangleMesh mesh =
      RemeshForLevel(input.initial_mesh, options, result->gsd_m, options.levels, progress);
  const LevelContext ctx{input,
                         options,
                         progress,
                         views,
                         result->pairs,
                         MeanRelativePairInformation(result->pair_details, options),
                         result->gsd_m};
  bool check_initial = options.restart_from_initial;
  for (int level = options.levels; level >= 0; --level) {
    const auto level_start = StageClock::now();
    double initial_zncc = std::numeric_limits<double>::quiet_NaN(), check_s = 0;
    TriangleMesh initial;
    if (level < options.levels) {
      const std::vector<char> subdivide =
          FacesToSubdivide(mesh, options.flat_tolerance_gsd * result->gsd_m * std::ldexp(1.0, level + 1));
      const size_t faces_before = mesh.num_faces();
      mesh = SubdivideMarked(mesh, subdivide);
      if (options.flat_tolerance_gsd > 0)
        spdlog::info("level {}: {} of {} faces subdivided ({} -> {} faces)", level,
                     std::count(subdivide.begin(), subdivide.end(), 1), faces_before,
                     faces_before, mesh.num_faces());
      SortSpatially(&mesh);
      if (check_initial) {
        const auto t0 = StageClock::now();
        initial = InitialSurfaceAt(input, options, result->gsd_m, level);
        initial_zncc = LevelZncc(input, views, result->pairs, options,
                                 result->gsd_m * std::ldexp(1.0, level), level, initial,
                                 options.rasterize_hit_maps);
        check_s = SecondsSince(t0);
      }
    }
    LevelStats stats;
    bool restarted = false;
    if (!RefineLevel(ctx, level, initial_zncc + kKeepMargin, &mesh, &stats)) {
      spdlog::info("level {}: the previous level's mean ZNCC {:.4f} does not beat the "
                   "initial surface's {:.4f} by {}; restarting from the initial surface",
                   level, stats.mean_zncc.front(), initial_zncc, kKeepMargin);
      mesh = RemeshForLevel(std::move(initial), options, result->gsd_m, level, progress);
      RefineLevel(ctx, level, std::numeric_limits<double>::quiet_NaN(), &mesh, &stats);
      restarted = true;
    } else if (!std::isnan(initial_zncc)) {
      check_initial = stats.mean_zncc.front() <= initial_zncc + kSkipCheckMargin;
      spdlog::info("level {}: kept the previous level's result (initial surface: mean ZNCC "
                   "{:.4f}, {:.1f} s to measure){}",
                   level, initial_zncc, check_s,
                   check_initial ? "" : "; finer levels do not measure it again");
    }
    stats.initial_zncc = initial_zncc;
    stats.restarted = restarted;
    stats.initial_check_s = check_s;
    stats.level_s = SecondsSince(level_start);
    result->levels.push_back(std::move(stats));
  }
  result->mesh = std::move(mesh);
}

// Step 5: KeepSignificantChanges with keep_initial_sigmas (-1: 2 for a mesh start, off for
// a DSM start). Refined from the true surface of a multi-date 0.3 m scene, roofs drift by
// the matching noise to 0.073 m NMAD without it, 0.012 m with it; from a stereo DSM it
// would undo real corrections the images make only as a whole (stereo 0.5 m roofs 0.79x
// -> 0.90x of the initial): docs/benchmarks-history.md, session 16.
void KeepInitialWithinNoise(const RefineInput& input, const RefineOptions& options,
                            RefineResult* result) {
  const double k = options.keep_initial_sigmas < 0 ? (input.initial_is_mesh ? 2.0 : 0.0)
                                                   : options.keep_initial_sigmas;
  if (!(k > 0) || result->mesh.height_sigma.size() != result->mesh.num_vertices()) return;
  // Offsets beyond 10 GSDs are changes whatever the noise (and beyond the reach looked at).
  const SignificanceStats stats =
      KeepSignificantChanges(input.initial_mesh, k, 10 * result->gsd_m, options.hold_boundary_xy,
                             &result->mesh);
  result->kept_initial_share = 1 - stats.mean_gain;
  spdlog::info("refine: the initial surface kept where the images do not contradict it beyond "
               "{} sigmas: {:.0f}% of the offsets of {} vertices undone",
               k, 100 * (1 - stats.mean_gain), stats.vertices);
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
  options.levels = ResolveLevels(user_options, result.gsd_m, input.initial_cell_m);
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

  // 4. Coarse to fine.
  CoarseToFine(input, options, progress, views, &result);

  // 5. The initial surface kept where the images do not contradict it beyond their noise.
  KeepInitialWithinNoise(input, options, &result);
  result.total_s = SecondsSince(start);
  progress.Report(1.0, "done");
  return result;
}

}  // namespace satmesh
