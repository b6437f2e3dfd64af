#pragma once
// The last step of the refinement: the initial surface is kept where the images do not
// contradict it beyond their noise (issue 16: "accept a change only when it is
// photo-consistent beyond noise"; issue 20: a true start stays put).
#include "core/mesh/mesh.h"

namespace satmesh {

struct SignificanceStats {
  size_t vertices = 0;   // vertices with the initial surface within reach along their normal
  double mean_gain = 1;  // mean share of their offset kept (1: all)
};

// For each vertex of `mesh` (the refined surface, with mesh->height_sigma from the images'
// Fisher information, metres), its offset d from `initial` along its normal (the nearer
// of the two intersections within max_offset_m; none: the vertex is left where it is)
// is kept with the weight g = z^4 / (z^4 + k^4), z = d / sigma: a change of less than
// about k sigmas, which the images' noise alone makes, returns to the initial surface; a
// larger one stays (at 2k, 94% of it). A vertex no image sees (sigma infinite) returns to
// the initial surface. hold_boundary_xy: the mesh's border vertices (tile edges) move
// vertically instead, so the outline stays where it is. Both meshes in the same frame; k > 0.
SignificanceStats KeepSignificantChanges(const TriangleMesh& initial, double k, double max_offset_m,
                                         bool hold_boundary_xy, TriangleMesh* mesh);

}  // namespace satmesh
