#pragma once
// The coarse mesh the refinement starts from (paper 3.3): the initial surface remeshed
// isotropically (CGAL) to a target edge length, so triangles are well shaped on walls
// too. Boundary edges are kept on the boundary (split, never moved inward).
#include "core/common/progress.h"
#include "core/mesh/mesh.h"

namespace satmesh {

// The crease angle of a DSM start's coarse remesh (RemeshForLevel): a wall's top and
// bottom lines, where a step of the grid meets a roof or the ground, stay sharp. From a
// DSM meshed at its full resolution whose walls are in place (synthetic 0.5 m stereo /
// tri-stereo / narrow stereo, sharp_dsm_noise_cells 0.2): facades @0.5 m 44.7 / 44.4 /
// 44.3% -> 46.9 / 46.4 / 46.5%, the DSM's own 46.2%, F 0.4 lower; from block averages (the
// default at 0.5 m) no change beyond 0.002 m and 0.2 points (docs/benchmarks-history.md,
// session 30).
constexpr double kDsmCreaseAngleDeg = 60;

struct CoarseMeshOptions {
  double target_edge_m = 2.0;  // target edge length, metres, > 0
  int iterations = 2;          // CGAL isotropic remeshing iterations, [1, 20] (3 before
                               // session 40: stereo 0.5 m 0.93-0.95x the time with 2, eight
                               // stereo / tri-stereo scenes at 0.3 and 0.5 m within 2% of
                               // roofs and 0.3 points, the Pléiades pairs within 0.0001)
  // A mesh of more faces is remeshed in blocks of about this many, in parallel (their
  // borders kept, then the band around the borders remeshed in pieces, also in parallel);
  // >= 1000. A block's remesh costs more per face the larger the block (stereo 0.5 m, 179k
  // faces of the DSM's 1 m grid remeshed to 581k at 1.0 m edges, both blocks together:
  // 9.5-10.4 s wall in blocks of 10000 faces, 6.4-7.3 s of 4000, 5.5 s of 1500, 13.6 s of
  // 30000; docs/benchmarks-history.md, session 27), while the band grows as blocks shrink
  // (session 38, the band in pieces: 2000 faces a block make the stereo job 6% faster than
  // 4000, with roofs 0.347 -> 0.349 m).
  size_t faces_per_block = 4000;
  // > 0: the input's creases, edges whose two faces' normals differ by more than this
  // (degrees), are kept where they are, as the border is: a DSM's walls keep their top and
  // bottom lines (RemeshForLevel: 60 for a DSM start). 0: none.
  double crease_angle_deg = 0;
  std::string Check() const;
};

// The target edge for remeshing a DSM's grid of cell `cell_m` (0: not a grid) to about
// `edge_m`. CGAL's remesh splits edges longer than 4/3 of the target and collapses those
// shorter than 4/5 of it. A grid at about the target (a 0.5 m job's 1 m grid, 1.006 m
// edges) has its legs within those bounds but its diagonals (sqrt(2) x cell) over them, so
// every flat part is re-triangulated. An edge between 0.9 and 1.066 x the cell is raised
// to 1.066 x the cell, where the diagonals are under the split bound: the flat parts stay
// as the grid made them and the remesh's work goes to the walls. Other edges are returned
// as they are. Stereo 0.5 m s1: the remesh 9.8 -> 5.4 s, 580k -> 477k faces. The refinement
// (LevelStartMesh) uses it from two pairs on: tri-stereo 0.5 m s1 / s2 roofs 0.333 / 0.346
// -> 0.321 / 0.333 m, F 42.9 / 49.9 -> 42.6 / 49.9, the job 30.5 / 31.7 -> 27.7 / 26.0 s.
// One pair keeps the finer remesh of the flat parts (as one pair never takes the grid
// start, ChooseCoarseStart): there the images add little to the initial surface's detail,
// and the real Pléiades pairs' held-out ZNCC fell 0.0004-0.0006 with it (stereo 0.5 m s1 /
// s2: the job 20.1 / 19.6 -> 16.3 / 15.2 s, roofs 0.350 / 0.362 -> 0.353 / 0.357 m, F
// 41.9 / 47.6 -> 41.7 / 47.5; docs/benchmarks-history.md, session 28).
double GridKeepingTargetEdge(double edge_m, double cell_m);

// Non-manifold faces of the input are dropped (logged). The result depends on the mesh
// and the options only, not on the number of threads. Throws Error{kInvalidInput} if
// nothing is left, Error{kCancelled} between remeshing iterations when progress says so.
// The result is sorted spatially (SortSpatially, core/mesh/topology.h).
TriangleMesh RemeshIsotropic(const TriangleMesh& mesh, const CoarseMeshOptions& options,
                             const Progress& progress = {});

}  // namespace satmesh
