#pragma once
// The mesh's resolution follows the surface (issue 18): between two levels only the faces
// where the surface bends are subdivided; planar parts (roofs, streets, walls) keep the
// coarser level's triangles, so each of their vertices gathers the pixels of a larger
// area (a lower-noise height) and the mesh has fewer faces.
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"

namespace satmesh {

// How far each vertex lies off the plane of its one-ring: |n_v . (v - mean of its
// neighbours)|, n_v the area-weighted vertex normal, metres (0 on any planar part,
// whatever the triangles' sizes; NaN for an isolated vertex).
std::vector<float> VertexBendingM(const TriangleMesh& mesh, const VertexAdjacency& adjacency);

// Faces to subdivide for the next level: those with a vertex bending by more than
// `tolerance_m` (VertexBendingM) or on an open border (tile seams keep the finer
// resolution on both sides), grown by one ring of faces so a crease is fine on both of its
// sides. tolerance_m <= 0: every face (uniform subdivision).
std::vector<char> FacesToSubdivide(const TriangleMesh& mesh, double tolerance_m);

// Subdivides those faces (SubdivideMarked) and sorts the result spatially; returns how many
// were subdivided. Between levels and in the crease pass (refine.cc).
size_t SubdivideNearCreases(double tolerance_m, TriangleMesh* mesh);

// Signed distance from each point to `surface` along its direction (unit): the nearest
// hit of the two rays p + t d and p - t d within reach_m (positive: the surface lies on
// the +d side; the + side wins a tie); NaN where neither ray meets it or d is zero.
// Also step 5's offsets (significance.cc).
std::vector<float> DistanceAlong(const RayScene& surface, const std::vector<Eigen::Vector3f>& points,
                                 const std::vector<Eigen::Vector3f>& directions, double reach_m);

// The coarse mesh refined where it cannot hold the initial surface's detail (used by
// level_start.cc's LevelStartMesh, which says when): faces from which `surface` (the initial
// surface's Embree scene) departs by more than tolerance_m along the face's normal, at the
// face's edge midpoints or centroid (measured within reach_m), are subdivided
// (SubdivideMarked), and the new vertices are put on the surface along their normals.
// Along the normals, not vertically: a DSM's blurred wall measured vertically departs
// everywhere, and pinning it to the DSM cost the 0.5 m scenes under overhangs
// (docs/benchmarks-history.md, session 18). *subdivided (when not null): the number of
// faces marked. also (when not null): per face, 1 to subdivide it whatever the departure.
TriangleMesh FollowInitialDetail(const TriangleMesh& mesh, const RayScene& surface,
                                 double tolerance_m, double reach_m, size_t* subdivided = nullptr,
                                 const std::vector<char>* also = nullptr);

}  // namespace satmesh
