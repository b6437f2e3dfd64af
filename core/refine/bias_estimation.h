#pragma once
// Per-image RPC bias estimation (DESIGN.md: a bias shift (col, row) in pixels per image,
// as in the paper). One reference view is held fixed; every other view, in breadth-first
// order over the pair graph, gets the 2D shift that maximises the mean ZNCC of the views
// already solved warped into it through the INITIAL surface (which stays fixed): a grid
// search at a coarse pyramid level, then quadratic fits on 3x3 grids down to full
// resolution. The pairs observe the biases only relative to each other: a common ground
// shift of the block is not observable from the images. Once every view is solved, that
// shift is fixed by MinimumNormDatum (the biases' a priori weights of an RPC block
// adjustment without control: the corrections as small as possible), not by the
// reference view alone; where the result is to sit on the initial surface
// (RefineOptions::register_to_initial, on for a mesh start), the shift is then searched
// for where the images agree best on that surface's relief (SurfaceDatum, in the .cc).
#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "core/common/progress.h"
#include "core/refine/refine.h"
#include "core/refine/view_setup.h"

namespace satmesh {

struct BiasOptions {
  int reference_view = -1;         // view held at zero; -1: the one in most pairs (first on ties)
  int coarse_level = 2;            // pyramid level of the grid search (reduced for small images), [0, 6]
  double search_radius_px = 6.0;   // grid search over +-radius per axis, full-res px, > 0
  double coarse_step_px = 2.0;     // grid spacing of the search, full-res px, > 0
  double final_step_px = 0.125;    // smallest 3x3 spacing at full resolution, full-res px, > 0
  int max_neighbours = 3;          // solved views a view is matched against (first in the
                                   // pair order: Refine gives them best score first), >= 1
  bool minimum_norm_datum = true;  // the block's common horizontal shift chosen so that the
                                   // corrections are smallest (MinimumNormDatum); false:
                                   // the reference view's RPC is the datum (correction 0)
  double solved_cache_mb = 1024;   // solved views' level data (rays, surface points) kept
                                   // for the views matched against them later, MB, >= 0
  RefineOptions refine;            // ZNCC window, visibility, virtual cameras (as the refinement)
  std::string Check() const;
};

struct BiasEstimate {
  int reference_view = -1;
  std::vector<Eigen::Vector2d> bias_col_row_px;  // per view, added to its RPC's bias (full-res px)
  std::vector<bool> solved;                      // false: no pair with a solved view (bias 0)
  std::vector<double> zncc_before, zncc_after;   // per view: mean ZNCC with solved views, level 0
  std::vector<std::pair<int, int>> pairs;        // the pairs it was estimated over
  Eigen::Vector2d datum_shift_m{0, 0};           // ground shift (east, north) the datum
                                                 // (MinimumNormDatum, then SurfaceDatum)
                                                 // applied to every solved view's correction
};

// The datum of a relative bias estimate. Shifting the whole block by a horizontal ground
// vector t changes each view's correction by J_v t (J_v: d(col,row)/d(east,north) of
// view v at `center`, a point of the local frame) and leaves every pair's agreement
// unchanged, so the images cannot tell. Vendor RPC biases are independent with zero mean,
// so the most probable datum makes the corrections smallest: t minimises
// sum over solved views of |c_v + J_v t|^2 (equal a priori weights; Grodecki & Dial 2003).
// Adds J_v t to each solved view's correction and records t in estimate->datum_shift_m.
void MinimumNormDatum(const std::vector<RpcModel>& rpcs, const LocalFrame& frame,
                                 const Eigen::Vector3d& center, BiasEstimate* estimate);

// Throws Error{kInvalidArgument} if options.Check() fails or a pair index is out of
// range, Error{kInvalidInput} for an empty initial mesh, Error{kCancelled} (checked per
// view and level) when progress says so. input's RPCs may already carry a bias; the
// estimate is added to it. A view's solved neighbours are taken in the order of `pairs`
// (best first), at most options.max_neighbours of them.
BiasEstimate EstimateViewBiases(const RefineInput& input,
                                const std::vector<std::pair<int, int>>& pairs,
                                const BiasOptions& options = {}, const Progress& progress = {});

// The same over views prepared once (PrepareViews; the RPCs are the views', pyramids with
// at least one level): what Refine calls.
BiasEstimate EstimateViewBiases(const RefineInput& input, const std::vector<PreparedView>& views,
                                const std::vector<std::pair<int, int>>& pairs,
                                const BiasOptions& options, const Progress& progress);

// Refine's first three steps as one call, for the CLI's bias and zncc commands: prepare
// the views, select the pairs as the refinement does, estimate the biases over them.
BiasEstimate EstimateRefineBiases(const RefineInput& input, const BiasOptions& options,
                                  const Progress& progress = {});

// input with each view's RPC bias increased by estimate.bias_col_row_px[v].
void ApplyViewBiases(const BiasEstimate& estimate, RefineInput* input);

}  // namespace satmesh
