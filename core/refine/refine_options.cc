#include "core/refine/refine_options.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace satmesh {
namespace {

using Range = OptionRange;
using R = RefineOptions;
using P = PairOptions;

// Cross-field checks the ranges cannot say (written once; wire names).
std::string CheckPairAngles(const PairOptions& p) {
  if (!(p.max_angle_deg > p.min_angle_deg))
    return "max_pair_angle_deg must be > min_pair_angle_deg (" + OptionValueText(p.min_angle_deg) +
           "), got " + OptionValueText(p.max_angle_deg);
  if (!(p.optimal_angle_deg >= p.min_angle_deg && p.optimal_angle_deg <= p.max_angle_deg))
    return "optimal_pair_angle_deg must be in [min_pair_angle_deg, max_pair_angle_deg] = [" +
           OptionValueText(p.min_angle_deg) + ", " + OptionValueText(p.max_angle_deg) + "], got " +
           OptionValueText(p.optimal_angle_deg);
  return "";
}

}  // namespace

const std::vector<RefineOptionInfo>& RefineOptionTable() {
  static const std::vector<RefineOptionInfo> table = {
      {"levels", &R::levels, Range::In(-1, 6),
       "coarsest pyramid level L (images at 1/2^L); -1: from the GSD and the initial surface's "
       "cell (the coarse triangle edge stays under max(max_coarse_edge_m, cell); 0 for a trusted "
       "DSM, trusted_initial)"},
      {"max_coarse_edge_m", &R::max_coarse_edge_m, Range::Above(0),
       "levels -1: bound of the coarse mesh's triangle edge, m"},
      {"iterations_per_level", &R::iterations_per_level, Range::In(0, 1000),
       "gradient steps per level"},
      {"coarsest_iterations_factor", &R::coarsest_iterations_factor, Range::In(1, 10),
       "the coarsest level (it starts from the initial surface) takes this times "
       "iterations_per_level gradient steps"},
      {"alpha", &R::alpha, Range::AtLeast(0), "weight of the photometric term (ZNCC)"},
      {"beta", &R::beta, Range::AtLeast(0),
       "weight of the thin-plate term (homogenised by 1/GSD^2)"},
      {"wall_beta_factor", &R::wall_beta_factor, Range::AboveTo(0, 1),
       "the thin-plate weight of a vertex of a wall face (steeper than 60 degrees) is this times "
       "beta: a wall needs the creases at its top and foot that a uniform thin plate rounds off "
       "(0.25: more of the facades, noisier walls); 1: uniform"},
      {"wall_patch_rings", &R::wall_patch_rings, Range::In(-1, 8),
       "at level 0 a wall vertex's step across its wall (faces steeper than 60 degrees) pools "
       "the gradients of the vertices of its wall within this many edges, where they agree "
       "beyond their noise: one pair's walls move as patches; 0: off; -1: 4 where one pair "
       "refines the surface, else off (several pairs move their walls themselves)"},
      {"roof_patch_rings", &R::roof_patch_rings, Range::In(0, 8),
       "at level 0 a roof or ground vertex the images constrain less than the initial "
       "surface's sigma does (its pull weight at least 0.5) takes its step along its normal "
       "from the vertices of its plane within this many edges, where they agree beyond their "
       "noise: weakly textured roofs move with their edges; 0: off"},
      {"plumb_walls", &R::plumb_walls, Range::In(-1, 1),
       "at level 0 a wall vertex the images constrain weakly is pulled towards the vertical "
       "through its wall's top where its start leans out there, in place of its start: a DSM's "
       "sloped walls hang plumb under the roof edges the images place; 0: off; 1: on; -1: on "
       "for a DSM start, off for a mesh start or a trusted one (trusted_initial: its walls are "
       "the user's model)"},
      {"step", &R::step, Range::Above(0), "gradient step, in units of (level GSD)^2"},
      {"max_step_gsd", &R::max_step_gsd, Range::Above(0),
       "clamp of one vertex's move per iteration, in level GSD"},
      {"momentum", &R::momentum, Range::FromBelow(0, 1),
       "each vertex's move adds this times what its last two moves agree on (heavy ball): a "
       "move the iterations agree on grows to 1 / (1 - this) steps, the swing between a "
       "pair's two directions and its groups is not carried; 0: plain gradient steps"},
      {"zncc_window_radius", &R::zncc_window_radius, Range::In(-1, 7),
       "ZNCC window radius r: (2r+1)^2 pixels; -1: 3 where one pair refines the surface (its "
       "vertices have one match each to go on), else 2"},
      {"min_window_valid", &R::min_window_valid, Range::AboveTo(0, 1),
       "min fraction of valid pixels in a ZNCC window"},
      {"variance_floor", &R::variance_floor, Range::Above(0),
       "floor of the ZNCC windows' variances (unit-range images)"},
      {"noise_variance_factor", &R::noise_variance_factor, Range::AtLeast(0),
       "the ZNCC variance floor is raised to this times the images' estimated noise variance at "
       "the level; 0: fixed floor"},
      {"visibility_tolerance_gsd", &R::visibility_tolerance_gsd, Range::Above(0),
       "depth test tolerance, in level GSD"},
      {"min_ray_cos", &R::min_ray_cos, Range::FromBelow(0, 1),
       "pixels whose ray meets the face at |cos| below this are ignored (grazing views)"},
      {"virtual_camera_grid_px", &R::virtual_camera_grid_px, Range::AtLeast(1),
       "spacing of exactly localised rays, in level pixels"},
      {"rasterize_hit_maps", &R::rasterize_hit_maps, {},
       "hit maps by z-buffer rasterization through the RFM; false: Embree ray casting"},
      {"hit_maps_every", &R::hit_maps_every, Range::In(1, 20),
       "hit maps made anew every N iterations (and at a level's first and last); in between, "
       "each pixel keeps its face and its hit point follows the moving face"},
      {"coarse_edge_px", &R::coarse_edge_px, Range::Above(0),
       "edge length of the coarse mesh at the coarsest level, in level pixels"},
      {"sharp_dsm_noise_cells", &R::sharp_dsm_noise_cells, Range::AtLeast(0),
       "> 0: a DSM start whose heights' noise at one cell (robust spread of its second "
       "differences) is at most this many cells is meshed at full resolution for the coarse "
       "remesh, its walls one cell wide (a DSM whose walls are in place: LiDAR, a city model); "
       "0: block-averaged to half the coarse triangle edge first"},
      {"flat_tolerance_gsd", &R::flat_tolerance_gsd, Range::AtLeast(0),
       "between levels only faces near a vertex off the plane of its neighbours by more than "
       "this many level GSDs are subdivided; planar parts keep larger triangles; 0: all faces"},
      {"initial_detail_gsd", &R::initial_detail_gsd, Range::AtLeast(0),
       "a full-resolution start (no coarser level) whose images resolve the median vertex's "
       "height to worse than this many GSDs: faces of the coarse mesh the initial surface "
       "departs from by more than that are subdivided, their new vertices put on it; 0: off"},
      {"flat_edge_px", &R::flat_edge_px, Range::In(-1, 16),
       "a DSM start remeshed at full resolution (no coarser level, grid_start 0, "
       "initial_detail_gsd > 0): its triangles' edge in pixels where the initial surface is "
       "planar, halved where the initial surface departs from them by more than "
       "initial_detail_gsd, down to half of coarse_edge_px (one pair: to the initial "
       "surface's cells, within half to one coarse_edge_px); at most coarse_edge_px: off; -1: "
       "2 x coarse_edge_px with more than one pair, 1.85 x with one pair (its faces the pair "
       "resolves to 2 GSD halved at once), else off"},
      {"grid_start", &R::grid_start, Range::In(-1, 1),
       "the coarse mesh of a DSM start: 1: the DSM's own grid at the level's triangle edge, the "
       "thin plate's umbrella weighing each neighbour by 1 / edge length, so the images form the "
       "walls (a mesh start: its triangles as they are); 0: isotropic remesh of the DSM mesh "
       "(its walls kept); -1: the grid where the images resolve the median vertex's height at "
       "full resolution to initial_detail_gsd, else (and for a trusted DSM, trusted_initial) the "
       "remesh"},
      {"crease_pass", &R::crease_pass, Range::In(-1, 1),
       "after the full-resolution level, the faces near its creases (off their neighbours' "
       "plane by more than flat_tolerance_gsd) are subdivided and the level runs again on them; "
       "1: on, 0: off, -1: on for a DSM start without coarser levels and with more than one pair, "
       "after an adaptive start (flat_edge_px) without subdividing: its creases are fine already"},
      {"restart_from_initial", &R::restart_from_initial, {},
       "below the coarsest level, continue from the initial surface unless the previous level's "
       "result matches the images better"},
      {"alternate_directions", &R::alternate_directions, {},
       "iterations other than a level's first and last (with more than one pair group: its "
       "first) use one direction per pair, alternating (half the work); false: both "
       "directions every iteration"},
      {"pairs_per_iteration", &R::pairs_per_iteration, Range::AtLeast(0),
       "> 0: a level's iterations other than its first and its last few take the pairs in "
       "turn, in groups of at least this many and at least half as many as the views; 0: "
       "every pair every iteration"},
      {"normalize_by_pair_count", &R::normalize_by_pair_count, {},
       "each vertex's photometric gradient is divided by the number of pair-directions that saw it"},
      {"min_height_confidence", &R::min_height_confidence, Range::AboveTo(0, 1),
       "floor of a vertex's height confidence (see height_sigma_gsd); the thin-plate weight is "
       "divided by it; 1: off"},
      {"height_sigma_gsd", &R::height_sigma_gsd, Range::AtLeast(0),
       "> 0: a vertex's height confidence from the images (Fisher information of its pixels under "
       "the images' noise): 1 where they determine its height to within this many level GSDs "
       "(1 sigma), (this / sigma)^2 below; 0: from the pairs' geometry"},
      {"initial_sigma_gsd", &R::initial_sigma_gsd, Range::AtLeast(0),
       "> 0: each vertex is pulled back towards where the level started it (at the coarsest "
       "level towards the initial surface; below it, in height only, towards the coarser level's "
       "result or the initial surface after a restart) by the share sigma_img^2 / (sigma_img^2 + "
       "this^2) of its images' height sigma (this: the start's 1-sigma error in level GSD), so "
       "weakly constrained parts do not drift; 0: off"},
      {"keep_initial_sigmas", &R::keep_initial_sigmas, Range::AtLeast(-1),
       "last step: each vertex keeps its offset from the initial surface with the weight z^4 / "
       "(z^4 + this^4), z = offset / its height sigma from the images, so a change within the "
       "images' noise returns to the initial surface; 0: off; -1: 2 for a mesh start (a model "
       "the user trusts, a previous result) or a trusted DSM start (trusted_initial), off for a "
       "DSM start (stereo DSMs err beyond noise)"},
      {"keep_initial_scales", &R::keep_initial_scales, Range::In(0, 6),
       "the last step first keeps the share of the offsets that is coherent beyond the images' "
       "noise over the vertices around each one on the same surface, at radii 8 x 2^i GSD (3: "
       "32, 16, 8 GSD, coarse to fine), so a start that is off smoothly (a roof 0.5 m too "
       "high) is corrected where each vertex's own offset is within its noise; then each "
       "vertex's own test on what is left; 0: per vertex only"},
      {"keep_initial_floor_gsd", &R::keep_initial_floor_gsd, Range::AtLeast(0),
       "the pooled tests' noise (keep_initial_scales) never below this many GSD: the bias "
       "estimation's residual (up to 0.05 px, through a pair at B/H 0.35) is common to a "
       "whole region, so no pooling gets below it"},
      {"register_to_initial", &R::register_to_initial, Range::In(-1, 1),
       "the result in the initial surface's frame: the bias estimation puts the image block "
       "where its pairs agree best on the initial surface (else the datum of minimum "
       "corrections), the last step takes off the rigid translation left; 1: on, 0: off, -1: on "
       "for a mesh start or a trusted DSM (trusted_initial: a model the user trusts), off for a "
       "DSM start"},
      {"smooth_offsets", &R::smooth_offsets, Range::In(-1, 1),
       "at full resolution the thin-plate term smooths each vertex's offset from where the "
       "level started it, not the surface, so the start's creases (walls, eaves, balconies) are kept; 1: on, 0: off, "
       "-1: on for a mesh start or a trusted DSM (trusted_initial: a model the user trusts), off "
       "for a DSM start (its noise)"},
      {"sunlit_pairs", &R::sunlit_pairs, Range::In(-1, 1),
       "a pixel whose surface point is lit under one image's sun and in shadow under the "
       "other's (by the current surface and the suns in the images' metadata) is left out of "
       "that pair: moving shadows of a multi-date set are not matched; 1: on, 0: off, -1: on "
       "for a mesh start or a trusted DSM (trusted_initial; a DSM's blurred walls cast wrong "
       "shadows)"},
      {"carry_coarse_levels", &R::carry_coarse_levels, Range::In(-1, 1),
       "below the coarsest level, start from the initial surface remeshed for the level and "
       "moved as the coarser level moved it, not from the coarser level's result (the start's "
       "walls and eaves kept, its error corrected at the coarse scale); 1: on, 0: off, -1: on "
       "for a mesh start (a model the user trusts)"},
      {"occluding_edge_bias_px", &R::occluding_edge_bias_px, Range::In(-1, 2),
       "the photometric term's outward bias at occluding edges, in full-resolution pixels "
       "(mixed pixels at a roof edge move with the roof between views, so ZNCC prefers walls "
       "about half a pixel out): the finished surface's walls (faces steeper than 60 degrees) "
       "are moved this far inward before the last step; 0: off; -1: 0.5 for a DSM start, off "
       "for a mesh start or a trusted one (trusted_initial: its walls are the user's model)"},
      {"trusted_initial", &R::trusted_initial, Range::In(0, 1),
       "1: the initial DSM is a model the user trusts as a mesh start is (LiDAR, a city model's "
       "DSM: its walls stand where the buildings' do): it is meshed at its own cells and "
       "remeshed at full resolution, not gridded (levels 0, grid_start), its walls are neither "
       "hung (plumb_walls) nor moved inward (occluding_edge_bias_px), its creases are kept "
       "(smooth_offsets), shadows are matched where lit (sunlit_pairs), a change within the "
       "images' noise returns to it (keep_initial_sigmas 2) and the result is registered to it "
       "(register_to_initial), as those options' -1 resolve; 0: a DSM from stereo matching "
       "(walls fattened, errors beyond the images' noise)"},
      {"hold_unseen", &R::hold_unseen, {},
       "vertices no pair-direction sees (occluded, grazing) do not move"},
      {"hold_boundary_xy", &R::hold_boundary_xy, {},
       "boundary vertices move vertically only (tile seams)"},
      {"estimate_bias", &R::estimate_bias, {},
       "estimate per-image RPC bias shifts over the initial surface before refining (added to "
       "images[].bias)"},
      {"min_pair_angle_deg", &P::min_angle_deg, Range::Open(0, 90),
       "pairs converging less are not used (the height is not constrained)"},
      {"max_pair_angle_deg", &P::max_angle_deg, Range::Open(0, 90),
       "pairs converging more are not used; above min_pair_angle_deg"},
      {"optimal_pair_angle_deg", &P::optimal_angle_deg, Range::Open(0, 90),
       "angle from which height precision no longer limits a pair; wider pairs score lower for "
       "occlusion; in [min_pair_angle_deg, max_pair_angle_deg]"},
      {"min_pair_overlap", &P::min_overlap, Range::In(0, 1),
       "fraction of the surface both images of a pair must see"},
      {"pair_partners_per_view", &P::partners_per_view, Range::AtLeast(1),
       "pairs each view gets where candidates allow"},
      {"max_pairs_per_image", &P::max_pairs_per_image, Range::AtLeast(1),
       "cap on the pairs of one image"},
      {"max_pairs", &P::max_pairs, Range::AtLeast(0), "pairs in all; 0: 1.5 per view, at least 10"},
      {"min_contrast", &P::min_contrast, Range::AtLeast(0),
       "images whose normalised standard deviation is below this are not used"},
  };
  return table;
}

const RefineOptionInfo* FindRefineOption(std::string_view name) {
  return FindOption(RefineOptionTable(), name);
}

std::string PairOptions::Check() const {
  RefineOptions options;
  options.pairs = *this;
  const std::string problem = CheckOptionRanges(RefineOptionTable(), options, /*nested_only=*/true);
  return problem.empty() ? CheckPairAngles(*this) : problem;
}

std::string RefineOptions::Check() const {
  const std::string problem = CheckOptionRanges(RefineOptionTable(), *this);
  if (!problem.empty()) return problem;
  if (zncc_window_radius == 0)
    return "zncc_window_radius must be -1 (from the pairs) or in [1, 7], got 0";
  return CheckPairAngles(pairs);
}

int ResolveLevels(const RefineOptions& options, double gsd_m, double initial_cell_m,
                  bool initial_is_mesh) {
  if (options.levels >= 0) return options.levels;
  // A trusted DSM is right at full resolution: a coarser level only smoothed its walls
  // (stereo 0.3 m s2 from the true DSM, F @0.5 m 87.5 with one, 91.5 without; session 47).
  if (options.trusted_initial > 0 && !initial_is_mesh) return 0;
  const double max_edge = std::max(options.max_coarse_edge_m, initial_cell_m);
  const auto edge = [&](int level) { return options.coarse_edge_px * gsd_m * std::ldexp(1.0, level); };
  int level = 0;
  while (level < 3 && edge(level + 1) <= max_edge + 1e-9) ++level;
  // Carried coarse levels (CarriesCoarseLevels) keep no wall of their own: one coarser
  // level is worth its cost up to twice the bound.
  if (level == 0 && options.CarriesCoarseLevels(initial_is_mesh) && edge(1) <= 2 * max_edge + 1e-9)
    level = 1;
  return level;
}

// One pair: 7x7 (stereo 0.5 m, 14 scenes: roofs NMAD 2-8% lower, facades within 0.2 points;
// 0.3 and 0.7 m: roofs 3-7% lower, facades 0.1-0.4 points lower; the Pleiades pairs' held-out
// ZNCC within 0.0003). Several pairs average their matches already: 7x7 windows cost the
// multi-date facades 0.7-1.2 points (docs/benchmarks-history.md, sessions 11 and 42).
int ResolveZnccWindowRadius(const RefineOptions& options, size_t num_pairs) {
  if (options.zncc_window_radius > 0) return options.zncc_window_radius;
  return num_pairs == 1 ? 3 : 2;
}

// One pair, stereo 0.5 m, 14 seeds (4 rings against none): under overhangs @0.5 m +0.6 to
// +2.1 points (mean +1.1), facades -0.4 to +1.8 (+0.7), F -0.1 to +1.1 (+0.5), roofs NMAD and
// perc-68 within 0.004 m; 0.3 and 0.4 m, 4 seeds: facades +0.5 to +0.9, F +0.4 to +0.6; the
// Pleiades held-out pairs within 0.0003. 3 rings: under overhangs 0.2-0.5 points less on
// every seed; 5: as 4. Tri-stereo and multi-date, whose pairs move their walls themselves
// (`--set wall_patch_rings=3`, tri-stereo s2, multi-date s1 / s2 at 0.5 m): under overhangs
// +1.1 to +2.4 but facades to -2.0 and F to -1.1 (docs/benchmarks-history.md, session 44).
int ResolveWallPatchRings(const RefineOptions& options, size_t num_pairs) {
  if (options.wall_patch_rings >= 0) return options.wall_patch_rings;
  return num_pairs == 1 ? 4 : 0;
}

}  // namespace satmesh
