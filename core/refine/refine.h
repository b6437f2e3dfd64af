#pragma once
// The refinement: photometric multi-view mesh refinement under the RFM (Rothermel et al.
// 2020), coarse to fine. One entry point, Refine(); everything runs in a LocalFrame.
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/common/progress.h"
#include "core/geo/local_frame.h"
#include "core/image/acquisition_info.h"
#include "core/image/image.h"
#include "core/mesh/mesh.h"
#include "core/refine/pairs.h"
#include "core/refine/refine_options.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

struct RefineView {
  std::string name;
  ImageF image;  // full-resolution window, raw digital numbers
  RpcModel rpc;  // pixel coordinates relative to the window (RpcModel::Cropped)
  AcquisitionInfo acquisition;  // sun and time, for pair selection (unset: unknown)
};

struct RefineInput {
  std::vector<RefineView> views;
  TriangleMesh initial_mesh;  // vertices in `frame` (x east, y north, z up; metres)
  // The initial surface meshed for triangles of about edge_m metres (in `frame`), for a
  // level that restarts from it (RefineOptions::restart_from_initial); empty: initial_mesh.
  std::function<TriangleMesh(double edge_m)> initial_for_edge;
  LocalFrame frame;
  double min_z = 0, max_z = 0;  // height range (frame z) the surface stays within
  double initial_cell_m = 0;    // resolution of the initial surface (DSM cell), 0: unknown
  double initial_mesh_cell_m = 0;  // initial_mesh's grid cell, m, where it is a DSM's grid; else 0
  bool initial_is_mesh = false;  // the job gave a mesh (RefineOptions::keep_initial_sigmas)
};

struct StageTimes {
  double hit_maps_s = 0;   // hit maps: rasterized, followed, or cast with Embree
  double gradient_s = 0, smoothness_s = 0, update_s = 0;
  double intersect_s = 0;  // the part of hit_maps_s spent in Embree's Intersect alone
  double sunlight_s = 0;   // the part of hit_maps_s spent marking the suns' light (sunlight.h)
};

struct LevelStats {
  int level = 0;
  int iterations = 0;
  int pair_directions = 0;             // photometric passes of one pair-direction, all
                                       // iterations together (pairs_per_iteration)
  int num_vertices = 0, num_faces = 0;
  double gsd_m = 0;                    // ground sampling distance of the level
  std::vector<double> mean_zncc;       // before each iteration's step (none after the last)
  double check_zncc = 0;               // the first iteration's over the pairs the initial
                                       // surface is compared on (InitialCheckPairs)
  // Mean ZNCC of the initial surface at this level, when compared with the previous
  // level's result (NaN: not compared); restarted: the level started from it.
  double initial_zncc = std::numeric_limits<double>::quiet_NaN();
  bool restarted = false;
  bool crease_pass = false;            // level 0 run again on its creases subdivided
  double initial_check_s = 0;          // meshing and measuring the initial surface
  // 10/50/90% quantiles of the vertices' height sigma from the images, in level GSD
  // (refine.cc, HeightConfidenceFromInformation); empty: not measured.
  std::vector<double> height_sigma_gsd_q;
  StageTimes times;
  double level_s = 0;                  // all of the level, initial_check_s included
};

struct RefineResult {
  TriangleMesh mesh;                   // in the input frame; height_sigma from the Fisher
                                       // information of the full-resolution pixels of all
                                       // pair-directions that see each vertex
  std::vector<std::pair<int, int>> pairs;  // selected (view indices), sorted
  std::vector<StereoPair> pair_details;    // the same, with angle, overlap and score
  int candidate_pairs = 0;                 // pairs that passed angle, overlap and contrast
  // estimate_bias: shift added to each view's RPC (full-res px, col/row), and its time.
  std::vector<Eigen::Vector2d> view_bias_px;
  double bias_s = 0;
  std::vector<LevelStats> levels;      // coarse to fine (options.levels resolved: ResolveLevels)
  double gsd_m = 0;                    // full-resolution GSD
  int grid_start = 0;                  // the coarse start taken (RefineOptions::grid_start
                                       // resolved: 1 the DSM's grid, 0 the remesh)
  bool adaptive_start = false;         // level 0 started from the adaptive remesh
                                       // (RefineOptions::flat_edge_px; level_start.h)
  // The mean share of the vertices' offsets from the initial surface undone by the last
  // step (RefineOptions::keep_initial_sigmas; 0: off or nothing undone).
  double kept_initial_share = 0;
  // The same step's translation from the images' datum to the initial surface's frame
  // (RegisterToInitial), subtracted from the result; the view biases stay in the images'
  // datum (a mesh shifted back by it agrees with them). Local frame, metres.
  Eigen::Vector3d registration_m{0, 0, 0};
  double total_s = 0;
};

// Mean ZNCC (the photo-consistency the refinement maximises) of `mesh` (in input.frame)
// over the given view pairs at pyramid level `level`, without changing anything. For
// held-out-view checks: measure pairs (held_out, used) before and after refinement.
double MeasureMeanZncc(const RefineInput& input, const TriangleMesh& mesh,
                       const std::vector<std::pair<int, int>>& pairs, int level,
                       const RefineOptions& options = {});

// The refinement's steps, in order: PrepareViews (normalise once, pyramids, pair
// candidates), SelectViewPairs, EstimateViewBiases (options.estimate_bias), then coarse to
// fine. Throws Error{kInvalidArgument} if options.Check() fails, Error{kInvalidInput} for
// unusable input (no usable pair: the message says why; empty mesh), Error{kCancelled}
// when progress says so.
RefineResult Refine(const RefineInput& input, const RefineOptions& options,
                    const Progress& progress = {});

}  // namespace satmesh
