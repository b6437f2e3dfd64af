#pragma once
// Adjacency and differential quantities of a TriangleMesh.
#include <Eigen/Core>
#include <vector>

#include "core/mesh/mesh.h"

namespace satmesh {

// Compressed one-ring adjacency (CSR): neighbours of vertex v are
// neighbors[offsets[v] .. offsets[v+1]), incident faces likewise.
struct VertexAdjacency {
  std::vector<int> neighbor_offsets, neighbors;
  std::vector<int> face_offsets, faces;
  std::vector<bool> is_boundary;  // on an open edge (an edge used by one face only)
};
// Neighbours of each vertex are sorted ascending; faces in ascending face order. O(n).
// Indices are not validated (call ValidateMesh first on untrusted meshes).
VertexAdjacency BuildVertexAdjacency(const TriangleMesh& mesh);

// Unit face normals (right-hand rule on the face's vertex order; zero for degenerate
// faces) and areas.
std::vector<Eigen::Vector3f> FaceNormals(const TriangleMesh& mesh);
std::vector<float> FaceAreas(const TriangleMesh& mesh);
// Area-weighted unit vertex normals.
std::vector<Eigen::Vector3f> VertexNormals(const TriangleMesh& mesh);

// 1 -> 4 subdivision: each edge split at its midpoint (shared edges split once).
// Original vertices keep their indices; midpoints follow. Face f becomes faces
// 4f..4f+3 (three corner triangles, then the centre one), orientation preserved.
TriangleMesh Subdivide1To4(const TriangleMesh& mesh);

// 1 -> 4 subdivision of the faces with marked[f] != 0 only, kept conforming (no vertex
// in the middle of another face's edge): an edge is split when a marked face has it; a
// face with two split edges has its third split too (repeated until none is left), so
// every face ends with 0 split edges (kept), 1 (bisected from the opposite corner into
// two) or 3 (1 -> 4 as Subdivide1To4). Orientation preserved; original vertices keep
// their indices, midpoints follow. marked.size() must be mesh.num_faces().
TriangleMesh SubdivideMarked(const TriangleMesh& mesh, const std::vector<char>& marked);

// Mean length of the unique (undirected) edges; 0 for a mesh without faces.
double MeanEdgeLength(const TriangleMesh& mesh);

// Unique undirected edges (a < b), sorted. O(n log n).
std::vector<Eigen::Vector2i> UniqueEdges(const TriangleMesh& mesh);

// Renumbers vertices along a Z-order curve and orders faces by their first vertex, so
// that everything indexed by face or vertex (normals, hits, gradients, Embree's
// primitives) is read in nearly sequential order by neighbouring pixels.
void SortSpatially(TriangleMesh* mesh);

}  // namespace satmesh
