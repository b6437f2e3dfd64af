#pragma once
// The mesh's resolution follows the surface (issue 18): between two levels only the faces
// where the surface bends are subdivided; planar parts (roofs, streets, walls) keep the
// coarser level's triangles, so each of their vertices gathers the pixels of a larger
// area (a lower-noise height) and the mesh has fewer faces.
#include <vector>

#include "core/mesh/mesh.h"
#include "core/mesh/topology.h"

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

}  // namespace satmesh
