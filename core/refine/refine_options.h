#pragma once
// Options of the refinement (DESIGN.md "The method"). Defaults were tuned on synthetic
// scenes from `satmesh synth` (see BENCHMARKS.md, "Why each default is what it is"). Each
// option's wire name, valid range and one-line help: RefineOptionTable() (refine_options.cc);
// the comments here say what the fields mean and their units.
#include <string>
#include <string_view>
#include <vector>

#include "core/common/option_table.h"

namespace satmesh {

// Stereo pair selection (core/refine/pairs.h): candidates, their score, the selection.
struct PairOptions {
  double min_angle_deg = 2.0;    // min intersection angle of the viewing directions: below,
                                 // a pair does not constrain the height
  double max_angle_deg = 60.0;   // max intersection angle
  double optimal_angle_deg = 20.0;  // angle from which the height precision no longer limits a
                                    // pair (B/H 0.35); wider pairs score lower for occlusion
  double min_overlap = 0.25;     // fraction of the surface both images must see
  int partners_per_view = 3;     // pairs each view gets where candidates allow
  int max_pairs_per_image = 6;   // cap on pairs that involve one image
  int max_pairs = 0;             // pairs in all; 0: 1.5 per view, at least 10 (pairs.cc)
  double min_contrast = 0.02;    // images whose normalised std is below this are dropped
  std::string Check() const;
};

struct RefineOptions {
  int levels = -1;                 // coarsest pyramid level L (images at 1/2^L);
                                   // -1: from the GSD and the initial surface (ResolveLevels;
                                   // 0 for a trusted DSM, trusted_initial)
  double max_coarse_edge_m = 2.0;  // levels -1: the coarse mesh's triangle edge stays under
                                   // max(this, the initial surface's cell), so that a coarse
                                   // start does not smooth away walls and structures of
                                   // twice this size
  int iterations_per_level = 20;   // gradient steps per level (docs/benchmarks-history.md,
                                   // sessions 14 and 32: 25 plain steps, 20 with momentum)
  double coarsest_iterations_factor = 2.0;  // the coarsest level, which starts from the
                                           // initial surface, takes this x
                                           // iterations_per_level gradient steps
  double alpha = 2.0;              // weight of the photometric term M
  double beta = 0.1;               // weight of the thin-plate term (homogenised by 1/GSD²)
  double wall_beta_factor = 1.0;   // the thin-plate weight of a vertex of a wall face
                                   // (kWallMaxNormalZ, edge_bias.h) is this x beta: a wall
                                   // needs the creases at its top and foot that a uniform
                                   // thin plate rounds off (0.25: multi-date facades +1.3 to
                                   // +3.8 points, but 0.3 m F -0.8; BENCHMARKS.md); 1: uniform
  int wall_patch_rings = -1;       // at level 0 a wall vertex's step across its wall pools the
                                   // gradients of its wall's vertices within this many edges
                                   // (gradient_patch.h: one pair's walls move as patches); 0: off;
                                   // -1: 4 where one pair refines the surface, else off
  int roof_patch_rings = 4;        // at level 0 a roof or ground vertex the images constrain
                                   // less than the initial surface's sigma does takes its step
                                   // along its normal from its plane's vertices within this many
                                   // edges (gradient_patch.h); 0: off
  int plumb_walls = -1;            // at level 0 a weakly constrained wall vertex is pulled
                                   // towards the vertical through its wall's top, where its
                                   // start leans out (plumb_walls.h); 0: off; 1: on; -1: on for
                                   // a DSM start, off for a mesh start
  double step = 0.5;               // gradient step, in units of (level GSD)²
  double max_step_gsd = 0.5;       // clamp of one vertex's move per iteration, in level GSD
  double momentum = 0.5;           // each vertex's move adds this x the move its last two
                                   // agree on (heavy ball, MomentumStep, AgreedMove;
                                   // docs/benchmarks-history.md, sessions 31 and 32)
  int zncc_window_radius = -1;     // ZNCC window (2r+1)²; -1: 3 with one pair, else 2
                                   // (ResolveZnccWindowRadius)
  double min_window_valid = 0.5;   // min fraction of valid pixels in a ZNCC window
  double variance_floor = 1e-4;    // floor of the windows' variances (unit-range images)
  double noise_variance_factor = 4.0;  // the floor is raised to this x the images' noise
                                       // variance at the level (NoiseSigma, Immerkær): windows
                                       // whose texture is not above the noise add little
                                       // gradient (ZNCC confidence); 0: fixed floor
  double visibility_tolerance_gsd = 2.0;  // depth test tolerance, in level GSD
  double min_ray_cos = 0.1;        // |cos| between ray and face normal below which a pixel is
                                   // ignored (grazing views)
  int virtual_camera_grid_px = 16; // spacing of exactly localised rays, in level pixels
  bool rasterize_hit_maps = true;  // hit maps by z-buffer rasterization through the RFM
                                   // (hit_map_raster.h); false: Embree ray casting
  int hit_maps_every = 2;          // hit maps made anew every N iterations and at a level's
                                   // first and last; in between each pixel keeps its face
                                   // and its point follows the face (FollowHitMaps)
  double coarse_edge_px = 2.0;     // edge length of the coarse mesh at level L, in level px
  double sharp_dsm_noise_cells = 0;  // > 0: a DSM start whose heights' noise at one cell
                                   // (DsmCellNoise) is at most this many cells is meshed at
                                   // its full resolution for the coarse remesh, its walls
                                   // one cell wide, not block-averaged to half the coarse
                                   // triangle edge first (tile_input.h, InitialMeshCell).
                                   // Off by default: it pays where the DSM's walls stand
                                   // where the buildings' do (LiDAR, a city model) and costs
                                   // where a stereo pipeline fattened them
  double flat_tolerance_gsd = 1.0;  // between levels only faces near a vertex off the plane
                                   // of its neighbours by more than this (GSD of the level
                                   // just finished) are subdivided; planar parts keep the
                                   // coarser triangles (mesh_resolution.h;
                                   // docs/benchmarks-history.md, session 12); 0: all
                                   // faces (the paper)
  double initial_detail_gsd = 0.25;  // a full-resolution start (no coarser level) whose
                                     // images resolve the median vertex's height to worse
                                     // than this many GSDs: faces of the coarse mesh the
                                     // initial surface departs from by more than that are
                                     // subdivided, their new vertices put on it
                                     // (level_start.cc, LevelStartMesh); 0: off
  double flat_edge_px = -1;        // a DSM start remeshed at full resolution (no coarser
                                   // level, grid_start 0, initial_detail_gsd > 0): its
                                   // triangles' edge in pixels where the initial surface is
                                   // planar, halved where the initial surface departs from
                                   // them by more than initial_detail_gsd down to half of
                                   // coarse_edge_px (one pair: to the initial surface's
                                   // cells, within half to one coarse_edge_px; a mesh
                                   // whose resolution follows the surface;
                                   // level_start.cc, AdaptiveStart); at most
                                   // coarse_edge_px: off; -1: 2 x coarse_edge_px with more
                                   // than one pair, 1.85 x with one pair (its faces the pair
                                   // resolves to 2 GSD halved at once), else off
  int grid_start = -1;             // the coarse mesh of a DSM start: 1: the DSM's own grid
                                   // at the level's triangle edge, the thin plate's
                                   // umbrella weighing each neighbour by 1 / edge length
                                   // (thin_plate.h), so the images, not the grid's one-cell
                                   // wall strips, form the walls (a mesh start: its
                                   // triangles as they are, the same umbrella); 0: CGAL's
                                   // isotropic remesh of the DSM mesh, whose walls are kept;
                                   // -1: the grid where the images resolve the median
                                   // vertex's height at full resolution to
                                   // initial_detail_gsd (multi-date sets), else the remesh
                                   // (stereo, tri-stereo, a trusted DSM; level_start.cc,
                                   // ChooseCoarseStart)
  int crease_pass = -1;            // after the full-resolution level, the faces near its
                                   // creases (a vertex off its neighbours' plane by more
                                   // than flat_tolerance_gsd) are subdivided and the level
                                   // is run again on them: the walls' triangles get 1 pixel
                                   // where a coarser level would have given the subdivision;
                                   // 1: on, 0: off, -1: on for a DSM start without
                                   // coarser levels and with more than one pair (after
                                   // an adaptive start, flat_edge_px, not subdivided:
                                   // refine.cc, CreasePass)
  bool restart_from_initial = true;  // below the coarsest level, continue from the initial
                                     // surface (remeshed at the level) unless the previous
                                     // level's result has a mean ZNCC higher by > 0.001
                                     // (refine.cc, kKeepMargin); once it is higher by
                                     // > 0.01, finer levels skip the comparison
                                     // (kSkipCheckMargin)
  bool alternate_directions = true;  // iterations other than a level's first and last (with
                                     // more than one pair group: its first) use one
                                     // direction per pair, alternating (half the work;
                                     // same accuracy on synthetic scenes, BENCHMARKS.md);
                                     // false: both directions every iteration (the paper)
  int pairs_per_iteration = 5;     // > 0: a level's iterations other than its first and
                                   // its last few take the pairs in turn, in groups of at
                                   // least this many and at least half as many as the
                                   // views (refine_level.h, PairGroups), and only their
                                   // views' hit maps are made or followed: a view set with
                                   // many pairs sees the same surface many times over
                                   // (refine_level.cc, kEveryPairAtTheEnd; multi-date 0.5
                                   // m, 10 pairs in 2 groups: 0.85x the time, history
                                   // session 40); 0: every pair every iteration
  bool normalize_by_pair_count = true;  // divide each vertex's photometric gradient by the
                                        // number of pair-directions that saw it (OpenMVS)
  double min_height_confidence = 0.1;  // floor of a vertex's height confidence (see
                                       // height_sigma_gsd); the thin-plate weight is
                                       // divided by it. 1: off (uniform beta)
  double height_sigma_gsd = 0.05;  // > 0: a vertex's height confidence comes from the
                                   // images (Fisher information of the pixels that see
                                   // it under the images' noise, refine.cc,
                                   // HeightConfidenceFromInformation): 1 where they
                                   // determine its height to within this, in level GSD
                                   // (1 sigma), falling as (this / sigma)² to
                                   // min_height_confidence; 0: from the pairs' geometry
                                   // only (HeightConfidence)
  double initial_sigma_gsd = 1.5;  // > 0: each vertex is pulled back towards where the
                                   // level started it (at the coarsest level towards the
                                   // initial surface; below it, in height only, towards the
                                   // coarser level's result or the initial surface after a
                                   // restart) in proportion to how little the images
                                   // constrain it (InitialPriorWeights:
                                   // sigma_img² / (sigma_img² + this²), this in level GSD,
                                   // the start's assumed 1-sigma error); 0: off
  double keep_initial_sigmas = -1;  // last step (KeepSignificantChanges): a vertex returns to
                                   // the initial surface unless its offset from it exceeds
                                   // about this many of its height sigmas from the images;
                                   // 0: off; -1: 2 for a mesh start or a trusted DSM
                                   // start (trusted_initial), off for a DSM start
  int keep_initial_scales = 3;     // the last step first keeps what is coherent beyond the
                                   // images' noise over neighbourhoods of radius 32, 16, 8
                                   // GSD (coarse to fine: PooledSignificantOffsets), then
                                   // tests what is left per vertex; 0: per vertex only
  double keep_initial_floor_gsd = 0.15;  // the pooled tests' noise never below this (GSD):
                                   // what the bias estimation leaves is common to a region
  int register_to_initial = -1;    // the result in the initial surface's frame: the bias
                                   // estimation puts the block where the images agree best
                                   // on the initial surface (SurfaceDatum; else the datum of
                                   // minimum corrections), and the last step takes off the
                                   // rigid translation left (RegisterToInitial); 1: on,
                                   // 0: off, -1: on for a mesh start or a trusted DSM
  int smooth_offsets = -1;         // at full resolution (level 0) the thin-plate term acts on
                                   // each vertex's offset from where the level started it
                                   // instead of on the surface itself, so the start's creases
                                   // (walls, eaves, balconies) are not rounded off (refine_level.cc);
                                   // 1: on, 0: off, -1: on for a mesh start or a trusted DSM
  int sunlit_pairs = -1;           // a pixel lit under one image's sun and in shadow under the
                                   // other's is left out of that pair-direction (moving
                                   // shadows of a multi-date set; the suns from the images'
                                   // metadata; sunlight.h); 1: on, 0: off, -1: on for a mesh
                                   // start or a trusted DSM (a DSM's blurred walls cast wrong
                                   // shadows)
  int carry_coarse_levels = -1;    // below the coarsest level, start from the initial surface
                                   // remeshed for the level and moved as the coarser level
                                   // moved it (CarryDisplacement), not from the coarser
                                   // level's result: coarse levels correct the start at their
                                   // scale, the start's walls and eaves are kept; 1: on,
                                   // 0: off, -1: on for a mesh start
  double occluding_edge_bias_px = -1;  // the photometric term's outward bias at occluding
                                   // edges, in full-resolution pixels (edge_bias.h: mixed
                                   // pixels move with the foreground): the finished surface's
                                   // walls are moved this far inward (DeflateOccludingEdges)
                                   // before the last step; 0: off; -1: 0.5 for a DSM start,
                                   // off for a mesh start (its walls are the user's model)
  int trusted_initial = 0;         // 1: the initial DSM is a model the user trusts as a mesh
                                   // start is (LiDAR, a city model's DSM: its walls stand
                                   // where the buildings' do): meshed at its own cells and
                                   // remeshed at full resolution (levels 0, grid_start),
                                   // its walls neither hung
                                   // (plumb_walls) nor moved inward
                                   // (occluding_edge_bias_px), its creases kept
                                   // (smooth_offsets), shadows matched where lit
                                   // (sunlit_pairs), a change within the images'
                                   // noise returns to it (keep_initial_sigmas 2), the
                                   // result is registered to it (register_to_initial): the
                                   // -1 defaults of those resolve so; 0: a stereo DSM
  bool hold_unseen = true;         // vertices no pair-direction of the iteration sees
                                   // (occluded, grazing, outside the images) do not move:
                                   // the surface stays where the images say nothing
  bool hold_boundary_xy = true;    // boundary vertices move vertically only (tile seams)
  bool estimate_bias = true;       // per-view RPC bias shift estimated over the initial surface
                                   // before refining (core/refine/bias_estimation.h; Pléiades:
                                   // ZNCC 0.67 -> 0.79, synthetic without bias: <= 0.11 px)
  PairOptions pairs;

  std::string Check() const;
  // A mesh start or a DSM start declared trusted (trusted_initial).
  bool TrustsInitial(bool initial_is_mesh) const { return initial_is_mesh || trusted_initial > 0; }
  // register_to_initial resolved for a mesh start, a trusted DSM start or a DSM start.
  bool RegistersToInitial(bool initial_is_mesh) const {
    return register_to_initial < 0 ? TrustsInitial(initial_is_mesh) : register_to_initial > 0;
  }
  // smooth_offsets resolved for a mesh start, a trusted DSM start or a DSM start.
  bool SmoothsOffsets(bool initial_is_mesh) const {
    return smooth_offsets < 0 ? TrustsInitial(initial_is_mesh) : smooth_offsets > 0;
  }
  // carry_coarse_levels resolved for a mesh start or a DSM start (a trusted one's too).
  bool CarriesCoarseLevels(bool initial_is_mesh) const {
    return carry_coarse_levels < 0 ? initial_is_mesh : carry_coarse_levels > 0;
  }
  // keep_initial_sigmas resolved for a mesh start, a trusted DSM start or a DSM start.
  double KeepInitialSigmas(bool initial_is_mesh) const {
    return keep_initial_sigmas < 0 ? (TrustsInitial(initial_is_mesh) ? 2.0 : 0.0)
                                   : keep_initial_sigmas;
  }
  // occluding_edge_bias_px resolved for a mesh start, a trusted DSM start or a DSM start.
  double OccludingEdgeBiasPx(bool initial_is_mesh) const {
    return occluding_edge_bias_px < 0 ? (TrustsInitial(initial_is_mesh) ? 0.0 : 0.5)
                                      : occluding_edge_bias_px;
  }
  // plumb_walls resolved for a mesh start, a trusted DSM start or a DSM start.
  bool HangsWallsPlumb(bool initial_is_mesh) const {
    return plumb_walls < 0 ? !TrustsInitial(initial_is_mesh) : plumb_walls > 0;
  }
  // sunlit_pairs resolved for a mesh start, a trusted DSM start or a DSM start.
  bool MatchesSunlitOnly(bool initial_is_mesh) const {
    return sunlit_pairs < 0 ? TrustsInitial(initial_is_mesh) : sunlit_pairs > 0;
  }
};

// Each refinement option declared once (core/common/option_table.h): wire name (the job's
// "options" in proto/job.schema.json, `--set name=value`, every message of Check()), field,
// range, one-line help. The options of `pairs` are written flat on the wire.
using RefineOptionInfo = OptionInfo<RefineOptions, PairOptions, &RefineOptions::pairs>;

// Every refinement option, in the schema's order.
const std::vector<RefineOptionInfo>& RefineOptionTable();
// nullptr for a name not in the table.
const RefineOptionInfo* FindRefineOption(std::string_view name);

// The coarsest level: options.levels, or for -1 the largest L in [0, 3] whose coarse
// triangle edge (coarse_edge_px x gsd_m x 2^L) is at most max(max_coarse_edge_m,
// initial_cell_m) (initial_cell_m <= 0: unknown): 0.3 m images L = 1, 0.503 m L = 0. Where
// the levels are carried (CarriesCoarseLevels: a mesh start) and that gives 0, 1 if its
// edge is at most twice the bound (0.5 m and 0.7 m images).
int ResolveLevels(const RefineOptions& options, double gsd_m, double initial_cell_m,
                  bool initial_is_mesh = false);

// The ZNCC window's radius: options.zncc_window_radius, or for -1 3 (7x7 pixels) where one
// pair refines the surface and 2 (5x5) otherwise (num_pairs 0: a measurement, not a
// refinement). One pair's vertex has one match to go on where several pairs average
// theirs: its window takes twice the pixels against the images' noise.
int ResolveZnccWindowRadius(const RefineOptions& options, size_t num_pairs);

// The wall patches' rings: options.wall_patch_rings, or for -1 4 where one pair refines the
// surface and 0 (off) otherwise: several pairs move their walls themselves (gradient_patch.h).
int ResolveWallPatchRings(const RefineOptions& options, size_t num_pairs);

}  // namespace satmesh
