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

// The result of FillHoles.
struct HoleFill {
  size_t filled = 0;   // holes triangulated
  size_t too_big = 0;  // holes left: larger than the limit
  size_t covered = 0;  // holes left: the mesh covers them from above (no gap to the images)
  size_t faces_added = 0;
};

// Fills the holes of a surface (x, y on the map, z up; metres): each border cycle that
// runs counter-clockwise seen from above (a hole in a surface whose faces face up; an
// outer border runs clockwise, as does a building's open base) whose extent (diagonal of
// its x, y box) is at most max_extent_m and which nothing covers from above (a ray up
// from its centroid hits no face: the ground's cut-out under a building is no gap) is
// triangulated, refined to its border's edge lengths and faired
// (CGAL::Polygon_mesh_processing::triangulate_refine_and_fair_hole).
// Faces CGAL cannot take (non-manifold) are kept as they are. New points and faces are
// appended; existing indices stay valid.
HoleFill FillHoles(double max_extent_m, std::vector<Eigen::Vector3d>* points,
                   std::vector<Eigen::Vector3i>* faces);

}  // namespace satmesh
