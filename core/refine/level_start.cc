#include "core/refine/level_start.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/coarse_mesh.h"
#include "core/refine/mesh_resolution.h"
#include "core/refine/refine_level.h"

namespace satmesh {
namespace {

// FollowInitialDetail looks for the initial surface within this many GSDs of the coarse
// mesh: farther, the coarse mesh is not an approximation of it there (a hole, a cut).
constexpr double kInitialDetailReachGsd = 4;

// One pair's adaptive start (AdaptiveStart): its remesh's edge in coarse edges (3.7 pixels
// of 2), and the height sigma (GSDs) within which the pair resolves a face, which is then
// halved at once. A 4-split of the 3.7-pixel remesh holds the 2-pixel remesh's density
// on the real Pleiades pair's flat parts (the 4-split of a 4-pixel remesh, 116k -> 464k
// faces against 519k, left its held-out pairs 0.0003-0.0005 lower).
constexpr double kOnePairFlatEdgeFactor = 1.85;
constexpr double kOnePairResolvedSigmaGsd = 2;

// The median vertex's height sigma from the images (+inf, unseen, sorts last); NaN for no
// vertex. The tests of LevelStartMesh and ChooseCoarseStart.
double MedianVertexSigma(std::vector<float> sigma) {
  if (sigma.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto middle = sigma.begin() + long(sigma.size() / 2);
  std::nth_element(sigma.begin(), middle, sigma.end());
  return *middle;
}

// A DSM start remeshed at full resolution: no coarser level, grid_start (resolved) 0. The
// one place that says where the adaptive start may apply (AdaptiveStart, ResolveFlatEdge).
bool RemeshedDsmAtFullResolution(const RefineOptions& options, bool initial_is_mesh) {
  return options.levels == 0 && !initial_is_mesh && options.grid_start == 0;
}

// AdaptiveStart: a DSM start remeshed at full resolution (no coarser level, grid_start 0,
// initial_detail_gsd on) gets triangles of flat_edge_px (resolved: ResolveFlatEdge; 4
// pixels from two pairs on) instead of coarse_edge_px where the initial surface is planar,
// and FollowInitialDetail halves them DetailRounds times (to 1 pixel; one pair: to the
// level's 2 pixels) where the initial
// surface departs from them: a mesh whose resolution follows the surface, large on roofs,
// streets and planar walls, fine at roof edges, wall feet and small structures. The larger
// flat triangles average more pixels; the creases get 1-2 pixel triangles from the start,
// so the crease pass (a second run of level 0) does not subdivide them (CreasePass; before
// session 47 it did not follow at all). Tri-stereo 0.5 m seeds 1-4, against the 2-pixel
// remesh with its crease pass (docs/benchmarks-history.md, session 36): roofs 0.318 / 0.332
// / 0.322 / 0.277 -> 0.310 / 0.308 / 0.287 / 0.262 m, facades @0.5 m +0.2 to +1.2 points, F
// -0.1 to +0.3, 0.6x the faces, the job 2.1x faster. One pair's start has 3.7-pixel triangles
// (kOnePairFlatEdgeFactor), and those whose vertices the pair resolves to 2 GSD
// (kOnePairResolvedSigmaGsd, LevelHeightSigma) are halved in the first round whatever the
// initial surface does: large triangles where one pair does not constrain the height (walls
// it sees at grazing incidence or not at all, occlusions, shadows), the 2-pixel density
// where it does. With 4-pixel triangles everywhere the real Pléiades pairs' held-out views
// fell (img_03's mean 0.78795 -> 0.78550): the flat parts of real images carry detail the
// larger triangles do not hold. Stereo 0.5 m s1 / s2 / seed 51 (docs/benchmarks-history.md,
// session 39): the job in 0.6-0.7x the time, the accuracy within the runs' noise, the
// Pléiades held-out pairs within 0.0002. One pair's start is subdivided down to the
// initial surface's own cells (FinestDetailPx), not below: one pass sees a wall from at
// most one side, at grazing incidence, and finer than its cells the initial surface holds
// no more detail to follow. At 0.5 m (a DSM block-averaged to 1 m) that is one round, 3.7
// -> 1.85 pixels: the second cost stereo 0.5 m (6 seeds) 1/0.83x the job's time for F +0.1
// to +0.3 and facades 0 to +0.2 points, roofs and under overhangs within the runs' noise,
// the Pleiades held-out pairs within 0.0002. At 0.7 m (a DSM meshed at its 0.7 m cells)
// it is two, down to 0.93 pixels, where the second round is worth F +1.1 / +1.3
// (docs/benchmarks-history.md, session 41).
bool AdaptiveStart(const RefineOptions& options, bool initial_is_mesh, int level) {
  return level == 0 && RemeshedDsmAtFullResolution(options, initial_is_mesh) &&
         options.initial_detail_gsd > 0 && options.flat_edge_px > options.coarse_edge_px;
}

}  // namespace

double LevelEdge(const RefineOptions& options, double gsd_m, int level) {
  return options.coarse_edge_px * gsd_m * std::ldexp(1.0, level);
}

// `mesh` remeshed isotropically to the triangle edge of `level`, a DSM start's creases kept
// (kDsmCreaseAngleDeg). With options.grid_start (resolved: ChooseCoarseStart): a DSM
// start's own grid with cells of that edge (block means), else `mesh` as it is. (The
// initial mesh's cells: InitialMeshCell. From the synthetic noisy DSM, 1-pixel cells at the
// coarse level of a 0.3 m job refine roofs 8-13% worse than 2-pixel cells, equal to the
// remesh's: docs/benchmarks-history.md, session 24.) edge_px > 0: the remesh's edge in
// pixels instead of coarse_edge_px (AdaptiveStart).
TriangleMesh RemeshForLevel(const RefineInput& input, TriangleMesh mesh,
                            const RefineOptions& options, double gsd_m, int level,
                            const Progress& progress, double grid_cell_m,
                            double edge_px) {
  if (options.grid_start > 0) {
    if (input.initial_is_mesh || !input.initial_for_edge) return mesh;
    return input.initial_for_edge(2 * LevelEdge(options, gsd_m, level));  // cells of one edge
  }
  const double level_edge_m = LevelEdge(options, gsd_m, level);
  const double edge_m = GridKeepingTargetEdge(
      edge_px > 0 ? level_edge_m * edge_px / options.coarse_edge_px : level_edge_m, grid_cell_m);
  const double creases = input.initial_is_mesh ? 0 : kDsmCreaseAngleDeg;
  return RemeshIsotropic(mesh, {.target_edge_m = edge_m, .crease_angle_deg = creases}, progress);
}

// The initial surface meshed for `level` (before remeshing): what a level below the
// coarsest measures and, if it wins, restarts from.
TriangleMesh InitialSurfaceAt(const RefineInput& input, const RefineOptions& options,
                              double gsd_m, int level) {
  if (!input.initial_for_edge) return input.initial_mesh;
  return input.initial_for_edge(LevelEdge(options, gsd_m, level));
}

// The mesh a level starts from, made from the initial surface: remeshed to the level's
// triangle edge (the coarsest level and a finer level of a carried start:
// CarriesCoarseLevels). At full resolution (level 0) where the images do not
// resolve the surface to initial_detail_gsd (the median vertex's height sigma from the
// pairs, LevelHeightSigma, above it: a stereo or tri-stereo pass), that mesh is subdivided
// where it cannot hold the initial surface's detail (FollowInitialDetail): the iterations
// at one level do not win back what the 2-pixel mesh smooths away (synthetic 0.7 m stereo
// and tri-stereo, F-score @0.5 m 2-3 points higher; multi-date views resolve it and lose
// 1 point of facades with it; docs/benchmarks-history.md, session 18). median_sigma_m: that
// median (NaN where the test did not run). AdaptiveStart: a DSM start's remesh at
// flat_edge_px, subdivided DetailRounds times.
TriangleMesh LevelStartMesh(const RefineInput& input, const RefineOptions& options,
                            const std::vector<PreparedView>& views,
                            const std::vector<std::pair<int, int>>& pairs, double gsd_m,
                            const Progress& progress, int level, double* median_sigma_m,
                            bool* adaptive_taken) {
  if (median_sigma_m) *median_sigma_m = std::numeric_limits<double>::quiet_NaN();
  if (adaptive_taken) *adaptive_taken = false;
  const bool coarsest = level == options.levels;  // GridKeepingTargetEdge from two pairs on
  const bool adaptive = AdaptiveStart(options, input.initial_is_mesh, level);
  const double grid_cell_m = coarsest && pairs.size() > 1 ? input.initial_mesh_cell_m : 0;
  TriangleMesh mesh = RemeshForLevel(
      input, coarsest ? input.initial_mesh : InitialSurfaceAt(input, options, gsd_m, level),
      options, gsd_m, level, progress, grid_cell_m, adaptive ? options.flat_edge_px : 0);
  if (level != 0 || options.grid_start > 0 || !(options.initial_detail_gsd > 0))
    return mesh;
  const double tolerance_m = options.initial_detail_gsd * gsd_m;
  const std::vector<float> sigma = LevelHeightSigma(input, views, pairs, options, gsd_m, 0, mesh);
  const double median = MedianVertexSigma(sigma);
  if (median_sigma_m) *median_sigma_m = median;
  // The test is at the level's own triangles (coarse_edge_px): a vertex of a remesh N times
  // as large averages N times the pixels across, its sigma about 1/N (stereo 0.5 m:
  // 1/N^1.6 from 3.7 to 6 pixels, so the test leans to "resolved" on larger starts).
  const double edge_px = adaptive ? options.flat_edge_px : options.coarse_edge_px;
  const double level_median = median * edge_px / options.coarse_edge_px;
  if (!(level_median > tolerance_m)) {
    spdlog::info("level 0: the images resolve the surface to {:.2f} m at {}-pixel triangles "
                 "(median vertex; {:.2f} m on the {}-pixel mesh), within {:.2f} m: the coarse "
                 "mesh is kept at {} pixels",
                 std::isnan(median) ? 0.0 : level_median, options.coarse_edge_px,
                 std::isnan(median) ? 0.0 : median, edge_px, tolerance_m, options.coarse_edge_px);
    // they form the detail themselves, on the level's own triangles
    if (adaptive)
      mesh = RemeshForLevel(input, input.initial_mesh, options, gsd_m, level, progress, grid_cell_m);
    return mesh;
  }
  if (adaptive_taken) *adaptive_taken = adaptive;
  const RayScene initial(input.initial_mesh);  // after the test: a DSM mesh of millions of faces
  const int rounds =
      adaptive ? DetailRounds(options.flat_edge_px,
                              FinestDetailPx(options.coarse_edge_px, pairs.size(),
                                             input.initial_mesh_cell_m / gsd_m))
               : 1;
  std::vector<char> resolved;  // one pair's adaptive start: halved in the first round
  if (adaptive && pairs.size() == 1)
    resolved = FacesWithinSigma(mesh, sigma, kOnePairResolvedSigmaGsd * gsd_m);
  size_t subdivided = 0;
  const size_t faces_before = mesh.num_faces();
  for (int round = 0; round < rounds; ++round) {
    size_t marked = 0;
    mesh = FollowInitialDetail(mesh, initial, tolerance_m, kInitialDetailReachGsd * gsd_m, &marked,
                               round == 0 && !resolved.empty() ? &resolved : nullptr);
    subdivided += marked;
    if (marked == 0) break;
  }
  SortSpatially(&mesh);
  const std::string or_resolved =
      resolved.empty() ? std::string()
                       : fmt::format(" or the pair resolves them ({} faces within {:.2f} m)",
                                     std::count(resolved.begin(), resolved.end(), 1),
                                     kOnePairResolvedSigmaGsd * gsd_m);
  spdlog::info(
      "level 0: the images resolve the surface to {:.2f} m at {}-pixel triangles (median "
      "vertex; {:.2f} m on the {}-pixel mesh): its {} faces subdivided in {} round(s) where "
      "the initial surface departs from them by more than {:.2f} m{} ({} marked; {} faces)",
      level_median, options.coarse_edge_px, median, edge_px, faces_before, rounds,
      tolerance_m, or_resolved, subdivided, mesh.num_faces());
  return mesh;
}

// Step 4a, RefineOptions::grid_start -1: the coarse start of a DSM start. The DSM's own
// grid at the levels' triangle edge (with the umbrella weighted by 1 / edge length) where
// the images resolve the median vertex's height at full resolution to initial_detail_gsd:
// there the images form the walls the grid lacks, better than from the remesh's walls
// (multi-date 0.5 m s1 / s2: facades 37.8 / 33.2 -> 48.8 / 38.9%, roofs 0.210 / 0.230 ->
// 0.199 / 0.223 m; docs/benchmarks-history.md, session 25). Else (a stereo pair, a
// tri-stereo: 0.4-1.0 GSD on the grid, against 0.03-0.17 GSD for multi-date sets) the
// remesh, which keeps the DSM's walls: one pass does not form them (stereo 0.5 m s1
// facades 24.2% from the remesh, 19.1% from the grid). One pair never takes the grid: the
// two views of a pass see the walls of at most two sides, and on the real Pléiades pair
// 01-03 (0.24 GSD on the grid, within the tolerance) the grid left the held-out view's
// pairs' ZNCC 0.0017 / 0.0014 lower than the remesh. The test measures the level-0
// grid through the initial check's pairs (InitialCheckPairs: a third of the jax set's 39
// pairs: 1.8 s on its 300 m tile, 3.6-6.2 s a large-job tile). Returns 1 for the grid, 0
// for the remesh; `grid`: that grid where it is the start of a job without coarser levels;
// `grid_zncc`: where the grid is taken, its mean ZNCC over those pairs, which level 0's
// initial-surface check compares with (the grid is what a restart there starts from). A
// trusted DSM (trusted_initial) keeps its walls: the remesh (multi-date 0.5 m s2 from the
// true DSM: facades @0.5 m 76.6% from the grid, 89.8% from the remesh; session 47).
int ChooseCoarseStart(const RefineInput& input, const RefineOptions& options,
                      const std::vector<PreparedView>& views,
                      const std::vector<std::pair<int, int>>& pairs, double gsd_m,
                      std::optional<TriangleMesh>* grid, double* grid_zncc) {
  if (options.grid_start >= 0) return options.grid_start;
  if (options.TrustsInitial(input.initial_is_mesh) || !input.initial_for_edge ||
      !(options.initial_detail_gsd > 0) || pairs.size() < 2)
    return 0;
  TriangleMesh mesh = input.initial_for_edge(2 * LevelEdge(options, gsd_m, 0));
  LevelMeasure measure =
      MeasureLevel(input, views, InitialCheckPairs(pairs, options), options, gsd_m, 0, mesh);
  const double median = MedianVertexSigma(std::move(measure.height_sigma));
  if (std::isnan(median)) return 0;
  const double tolerance_m = options.initial_detail_gsd * gsd_m;
  const bool resolves = median <= tolerance_m;
  spdlog::info("refine: the images resolve the DSM's grid at full resolution to {:.2f} m "
               "(median vertex, {}within {:.2f} m): the coarse mesh is {}",
               median, resolves ? "" : "not ", tolerance_m,
               resolves ? "the DSM's grid, the images form the walls"
                        : "the DSM mesh remeshed, its walls kept");
  if (resolves && options.levels == 0) *grid = std::move(mesh);
  if (resolves && options.rasterize_hit_maps) *grid_zncc = measure.mean_zncc;  // as the check
  return resolves ? 1 : 0;
}

double ResolveFlatEdge(const RefineOptions& options, bool initial_is_mesh, size_t num_pairs) {
  if (options.flat_edge_px >= 0) return options.flat_edge_px;
  if (!RemeshedDsmAtFullResolution(options, initial_is_mesh) || num_pairs == 0)
    return options.coarse_edge_px;
  return (num_pairs > 1 ? 2 : kOnePairFlatEdgeFactor) * options.coarse_edge_px;
}

std::vector<char> FacesWithinSigma(const TriangleMesh& mesh, const std::vector<float>& sigma,
                                   double limit_m) {
  std::vector<char> within(mesh.num_faces(), 0);
  if (sigma.size() != mesh.num_vertices()) return within;
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3i& t = mesh.faces[f];
    within[f] = sigma[size_t(t[0])] <= limit_m && sigma[size_t(t[1])] <= limit_m &&
                sigma[size_t(t[2])] <= limit_m;
  }
  return within;
}

double FinestDetailPx(double coarse_edge_px, size_t num_pairs, double initial_cell_px) {
  const double half = coarse_edge_px / 2;
  if (num_pairs > 1) return half;
  return std::clamp(initial_cell_px, half, coarse_edge_px);
}

int DetailRounds(double flat_edge_px, double finest_px) {
  int rounds = 1;
  for (double edge = flat_edge_px / 2; edge > 1.01 * finest_px; edge /= 2) ++rounds;
  return rounds;
}

}  // namespace satmesh
