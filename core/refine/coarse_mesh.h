#pragma once
// The coarse mesh the refinement starts from (paper 3.3): the initial surface remeshed
// isotropically (CGAL) to a target edge length, so triangles are well shaped on walls
// too. Boundary edges are kept on the boundary (split, never moved inward).
#include "core/common/progress.h"
#include "core/mesh/mesh.h"

namespace satmesh {

struct CoarseMeshOptions {
  double target_edge_m = 2.0;  // target edge length, metres, > 0
  int iterations = 3;          // CGAL isotropic remeshing iterations, [1, 20]
  // A mesh of more faces is remeshed in blocks of about this many, in parallel (their
  // borders kept, then the band around the borders remeshed as one); >= 1000. A block's
  // remesh costs more per face the larger the block (stereo 0.5 m, 179k faces of the DSM's
  // 1 m grid remeshed to 581k at 1.0 m edges, both blocks together: 9.5-10.4 s wall in
  // blocks of 10000 faces, 6.4-7.3 s of 4000, 5.5 s of 1500, 13.6 s of 30000), while the
  // band, remeshed by one thread, grows as blocks shrink (2.5 s at 4000, 3.1 s at 1500;
  // docs/benchmarks-history.md, session 27).
  size_t faces_per_block = 4000;
  std::string Check() const;
};

// Non-manifold faces of the input are dropped (logged). The result depends on the mesh
// and the options only, not on the number of threads. Throws Error{kInvalidInput} if
// nothing is left, Error{kCancelled} between remeshing iterations when progress says so.
// The result is sorted spatially (SortSpatially).
TriangleMesh RemeshIsotropic(const TriangleMesh& mesh, const CoarseMeshOptions& options,
                             const Progress& progress = {});

// Renumbers vertices along a Z-order curve and orders faces by their first vertex, so
// that everything indexed by face or vertex (normals, hits, gradients, Embree's
// primitives) is read in nearly sequential order by neighbouring pixels.
void SortSpatially(TriangleMesh* mesh);

}  // namespace satmesh
