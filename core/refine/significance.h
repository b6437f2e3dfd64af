#pragma once
// The last step of the refinement: the initial surface is kept where the images do not
// contradict it beyond their noise (issue 16: "accept a change only when it is
// photo-consistent beyond noise"; issue 20: a true start stays put).
#include <Eigen/Core>

#include <vector>

#include "core/mesh/mesh.h"

namespace satmesh {

struct SignificanceStats {
  size_t vertices = 0;   // vertices with the initial surface within reach along their normal
  double mean_gain = 1;  // mean share of their offset kept (1: all)
  Eigen::Vector3d registration_m{0, 0, 0};  // RegisterToInitial's translation, subtracted
};

// The rigid translation T that best explains the offsets d_v of a refined surface from
// the initial one along the vertex normals n_v (d_v = n_v . T + a real change + noise):
// weighted least squares, weights 1 / sigma_v^2, robust (Cauchy at 2 sigma_v, then Tukey's
// biweight at 4 sigma_v, so real changes do not pull it), with a prior T ~ N(0,
// prior_sigma_m^2) per axis so that a direction no normal observes (a flat tile says
// nothing about east-north) stays at 0. Vertices with sigma_v not finite or not > 0 are
// left out. Where the images' datum (the bias estimation's choice of the block's common
// shift, which the images cannot observe: MinimumNormDatum) differs from the initial
// mesh's frame, every seen wall and slope shows it as the same T.
Eigen::Vector3d RegisterToInitial(const std::vector<Eigen::Vector3f>& normals,
                                  const std::vector<double>& offsets,
                                  const std::vector<double>& sigmas, double prior_sigma_m);

// For each vertex of `mesh` (the refined surface, with mesh->height_sigma from the images'
// Fisher information, metres), its offset d from `initial` along its normal (the nearer
// of the two intersections within max_offset_m; none: the vertex is left where it is)
// is kept with the weight g = z^4 / (z^4 + k^4), z = d / sigma: a change of less than
// about k sigmas, which the images' noise alone makes, returns to the initial surface; a
// larger one stays (at 2k, 94% of it). A vertex no image sees (sigma infinite) returns to
// the initial surface. hold_boundary_xy: the mesh's border vertices (tile edges) move
// vertically instead, so the outline stays where it is. Both meshes in the same frame;
// k > 0, or k = 0 with register_to_initial (the registration alone, every offset kept).
// register_to_initial: first the translation RegisterToInitial finds (prior sigma
// max_offset_m) is taken off the whole mesh (border vertices: its vertical part) and the
// offsets, so the result is the initial surface's frame, changed where the images say so.
SignificanceStats KeepSignificantChanges(const TriangleMesh& initial, double k, double max_offset_m,
                                         bool hold_boundary_xy, bool register_to_initial,
                                         TriangleMesh* mesh);

}  // namespace satmesh
