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

// The displacement a level made carried onto another mesh of the same surface: each vertex
// of `target` moves as the point of `start` closest to it moved (`start` and `end`: one
// topology, the level's mesh before and after its iterations; barycentric in the closest
// face, CGAL's AABB tree), times its up-facing weight (1 where its normal is within 37
// degrees of up, n_z >= 0.8; 0 from 60 degrees, n_z <= 0.5: walls, undersides; linear
// between) and the weight of that face being of its surface (1 where their normals are
// within 18 degrees, 0 from 37: near a wall a coarse mesh bridges roof and street). So a finer level of a mesh start begins from the user's mesh, walls and eaves
// kept, with roofs and ground corrected by what the coarser level found at its scale,
// rather than from the coarser level's remesh (CoarseToFine; walls moved too cost 3 points
// of facades on a stereo 0.5 m scene, docs/benchmarks-history.md, session 21). All three
// meshes in one frame (x east, y north, z up; one origin). Throws Error{kInvalidArgument} if start and end differ in vertices or
// start has no face.
TriangleMesh CarryDisplacement(const TriangleMesh& start, const TriangleMesh& end,
                               TriangleMesh target);

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
