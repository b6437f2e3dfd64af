#pragma once
// The image block's datum on a surface with relief (RefineOptions::register_to_initial):
// the pairs see only the views' biases relative to each other, but through a fixed
// initial surface with walls and roof edges the images agree best where the whole block
// sits on it. Used by the bias estimation (bias_estimation.h) after the datum of minimum
// corrections (MinimumNormDatum).
#include <Eigen/Core>

#include <utility>
#include <vector>

#include "core/common/progress.h"
#include "core/geo/local_frame.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/refine_options.h"
#include "core/refine/view_setup.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

// d(col, row) / d(east, north) of each view at `center` (a point of the local frame), px
// per metre: how a common ground shift of the block moves each view's correction.
std::vector<Eigen::Matrix2d> DatumJacobians(const std::vector<RpcModel>& rpcs,
                                            const LocalFrame& frame, const Eigen::Vector3d& center);

// The fixed surface and the views the datum is measured on.
struct DatumProblem {
  const std::vector<PreparedView>& views;       // pyramids, normalised
  const std::vector<RpcModel>& rpcs;            // per view, with the relative biases solved
  const LocalFrame& frame;
  const RayScene& scene;                        // the initial surface
  const std::vector<Eigen::Vector3f>& normals;  // its face normals
  Eigen::Vector3d box_min, box_max;             // its box, heights over the input's range
  const RefineOptions& options;                 // ZNCC window, visibility, virtual cameras
  double gsd_m = 0;                             // mean full-resolution GSD of the views
};

struct SurfaceDatumResult {
  Eigen::Vector2d t{0, 0};                    // the block's ground shift (east, north), m
  double zncc_before = 0, zncc_after = 0;     // mean ZNCC of the pairs at t0 and at t (level 0)
};

// The block's common ground shift t on the initial surface (DatumObjective), from t0:
// 3x3 quadratic steps of 1 and 0.5 GSD at level 1, then 0.25 and 0.125 GSD at full
// resolution (all four there for small images; level 1 alone leaves ~0.15 m where full
// resolution finds the datum to ~0.05 m, a multi-date 0.5 m scene, session 17), over the
// middle of the surface only (each view's window cropped to 384 x 384 GSD, its RPC moved
// by J_v t). Returns t and the pairs' mean ZNCC at t0 and at t. Throws Error{kCancelled}
// when progress says so.
SurfaceDatumResult SurfaceDatum(const DatumProblem& problem, const std::vector<Eigen::Matrix2d>& jacobians,
                                const std::vector<std::pair<int, int>>& pairs,
                                const Eigen::Vector2d& t0, int coarse_level, const Progress& progress);

}  // namespace satmesh
