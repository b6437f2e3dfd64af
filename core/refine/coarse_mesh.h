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
  // borders kept, then the band around the borders remeshed as one); >= 1000.
  size_t faces_per_block = 10000;
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
