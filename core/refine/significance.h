#pragma once
// The last step of the refinement: the initial surface is kept where the images do not
// contradict it beyond their noise (issue 16: "accept a change only when it is
// photo-consistent beyond noise"; issue 20: a true start stays put).
#include <Eigen/Core>

#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

namespace satmesh {

struct SignificanceStats {
  size_t vertices = 0;   // vertices with the initial surface within reach along their normal
  double mean_gain = 1;  // mean share of their offset kept (1: all)
  double pooled_share = 0;  // mean share kept by the pooled tests (options.scales)
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

struct SignificanceOptions {
  double k = 2;               // sigmas (RefineOptions::keep_initial_sigmas); 0: registration only
  double max_offset_m = 1;    // reach along the normal to the initial surface
  bool hold_boundary_xy = true;
  bool register_to_initial = false;
  // Pooled tests before each vertex's own (RefineOptions::keep_initial_scales): at radii
  // 8 x 2^i GSD, i = scales - 1 .. 0 (coarse to fine); 0: each vertex alone.
  int scales = 0;
  double gsd_m = 0;           // the images' GSD (> 0 when scales > 0)
  double floor_gsd = 0.15;    // RefineOptions::keep_initial_floor_gsd
};

// A share of `offsets` kept where it is coherent around each vertex beyond the images'
// noise (one radius of KeepSignificantChanges's coarse-to-fine tests): for vertex v, the
// mean of the offsets of the vertices around it on the same surface (reached from v over
// the mesh's edges through vertices whose normals are within 37 degrees of v's, within
// radius_m; weights (1 - r²/R²)² / sigma², robust: from their median, Tukey's biweight at
// 4 of each vertex's sigmas), its noise sigma_m² = the weighted mean's variance from the
// vertices' sigmas + floor_m², and the returned value is g(mean / sigma_m) x mean,
// g(z) = z^4 / (z^4 + k^4). Vertices whose offset is NaN, or whose sigma
// is not finite and > 0, count for nothing; a vertex with none around it gets 0.
// `adjacency`: BuildVertexAdjacency(mesh), built once by the caller for all radii.
std::vector<double> PooledSignificantOffsets(const TriangleMesh& mesh,
                                             const VertexAdjacency& adjacency,
                                             const std::vector<Eigen::Vector3f>& normals,
                                             const std::vector<double>& offsets,
                                             const std::vector<double>& sigmas, double radius_m,
                                             double floor_m, double k);

// For each vertex of `mesh` (the refined surface, with mesh->height_sigma from the images'
// Fisher information, metres), its offset d from `initial` along its normal (the nearer
// of the two intersections within max_offset_m; none: the vertex is left where it is)
// is kept as far as the images support it beyond their noise, and the rest returns to
// the initial surface. With options.scales > 0, first coarse to fine what is coherent
// over a neighbourhood (PooledSignificantOffsets at radii 32, 16, 8 GSD for 3 scales:
// a smooth error of the start, a building's roof off by 0.5 m, is corrected by hundreds
// of vertices whose offsets are each within their noise), each radius on what the
// coarser ones left; the pooled noise is floored at floor_gsd (the bias estimation's
// residual, up to 0.05 px through a pair at B/H 0.35, is the same over a
// whole region: no pooling gets below it). Then what is left of each vertex's offset, r,
// with the weight g = z^4 / (z^4 + k^4), z = r / sigma: a change of less than about k
// sigmas, which the images' noise alone makes, returns to the initial surface; a larger
// one stays (at 2k, 94% of it). A vertex no image sees (sigma infinite) returns to the
// initial surface: its neighbours' coherent move is evidence about them, not about a
// soffit or a wall foot they hide (refined from the true multi-date 0.5 m surface, under
// overhangs 97.8 -> 98.1%; docs/benchmarks-history.md, session 22). hold_boundary_xy: the mesh's border vertices (tile edges) move
// vertically instead, so the outline stays where it is. Both meshes in the same frame;
// k > 0, or k = 0 with register_to_initial (the registration alone, every offset kept).
// register_to_initial: first the translation RegisterToInitial finds (prior sigma
// max_offset_m) is taken off the whole mesh (border vertices: its vertical part) and the
// offsets, so the result is the initial surface's frame, changed where the images say so.
SignificanceStats KeepSignificantChanges(const TriangleMesh& initial,
                                         const SignificanceOptions& options, TriangleMesh* mesh);

}  // namespace satmesh
