#include "core/refine/mesh_resolution.h"

#include <cmath>
#include <limits>

namespace satmesh {

std::vector<float> VertexBendingM(const TriangleMesh& mesh, const VertexAdjacency& adjacency) {
  const std::vector<Eigen::Vector3f> normals = VertexNormals(mesh);
  std::vector<float> bending(mesh.num_vertices(), std::numeric_limits<float>::quiet_NaN());
  for (size_t v = 0; v < mesh.num_vertices(); ++v) {
    const int begin = adjacency.neighbor_offsets[v], end = adjacency.neighbor_offsets[v + 1];
    if (begin == end) continue;
    Eigen::Vector3f mean = Eigen::Vector3f::Zero();
    for (int i = begin; i < end; ++i) mean += mesh.vertices[adjacency.neighbors[i]];
    mean /= float(end - begin);
    bending[v] = std::abs(normals[v].dot(mesh.vertices[v] - mean));
  }
  return bending;
}

std::vector<char> FacesToSubdivide(const TriangleMesh& mesh, double tolerance_m) {
  const size_t nf = mesh.num_faces();
  if (!(tolerance_m > 0)) return std::vector<char>(nf, 1);
  const VertexAdjacency adjacency = BuildVertexAdjacency(mesh);
  const std::vector<float> bending = VertexBendingM(mesh, adjacency);
  std::vector<char> vertex_marked(mesh.num_vertices(), 0);
  for (size_t v = 0; v < mesh.num_vertices(); ++v)
    vertex_marked[v] = adjacency.is_boundary[v] || !(bending[v] <= tolerance_m);
  // A face with a marked vertex is subdivided; so is every face sharing a vertex with it.
  std::vector<char> seed(nf, 0);
  for (size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) seed[f] |= vertex_marked[mesh.faces[f][k]];
  std::vector<char> near_seed(mesh.num_vertices(), 0);
  for (size_t f = 0; f < nf; ++f)
    if (seed[f])
      for (int k = 0; k < 3; ++k) near_seed[mesh.faces[f][k]] = 1;
  std::vector<char> marked(nf, 0);
  for (size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) marked[f] |= near_seed[mesh.faces[f][k]];
  return marked;
}

}  // namespace satmesh
