#include "core/refine/mesh_resolution.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/mesh/topology.h"
#include "core/refine/coarse_mesh.h"

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

std::vector<float> DistanceAlong(const RayScene& surface, const std::vector<Eigen::Vector3f>& points,
                                 const std::vector<Eigen::Vector3f>& directions, double reach_m) {
  const size_t n = points.size();
  std::vector<float> distance(n, std::numeric_limits<float>::quiet_NaN());
  // The rays in chunks: a 0.5 m stereo tile's start measures 2.3M points (52 bytes of ray
  // and hit each way), which all at once made the job's peak (469 MB, +130 MB over the
  // level's iterations).
  constexpr size_t kChunk = size_t(1) << 16;
  std::vector<Ray> rays(2 * std::min(n, kChunk));
  std::vector<RayHit> hits(rays.size());
  for (size_t first = 0; first < n; first += kChunk) {
    const size_t count = std::min(kChunk, n - first);
    for (size_t j = 0; j < count; ++j) {
      const size_t i = first + j;
      for (int s = 0; s < 2; ++s) {
        Ray& r = rays[2 * j + s];
        r.origin = points[i];
        r.direction = s == 0 ? directions[i] : Eigen::Vector3f(-directions[i]);
        r.t_near = 0.f;
        r.t_far = directions[i].squaredNorm() > 0 ? float(reach_m) : 0.f;  // no direction: no hit
      }
    }
    surface.Intersect(rays.data(), hits.data(), 2 * count);
    for (size_t j = 0; j < count; ++j) {
      const RayHit &up = hits[2 * j], &down = hits[2 * j + 1];
      if (up.hit() && (!down.hit() || up.t <= down.t)) distance[first + j] = up.t;
      else if (down.hit()) distance[first + j] = -down.t;
    }
  }
  return distance;
}

TriangleMesh FollowInitialDetail(const TriangleMesh& mesh, const RayScene& surface,
                                 double tolerance_m, double reach_m, size_t* subdivided,
                                 const std::vector<char>* also) {
  const size_t nf = mesh.num_faces();
  const std::vector<Eigen::Vector3f> normals = FaceNormals(mesh);
  std::vector<Eigen::Vector3f> points, directions;
  points.reserve(4 * nf);
  directions.reserve(4 * nf);
  for (size_t f = 0; f < nf; ++f) {
    const Eigen::Vector3f a = mesh.vertices[mesh.faces[f][0]], b = mesh.vertices[mesh.faces[f][1]],
                          c = mesh.vertices[mesh.faces[f][2]];
    for (const Eigen::Vector3f& p : {Eigen::Vector3f((a + b) / 2), Eigen::Vector3f((b + c) / 2),
                                     Eigen::Vector3f((c + a) / 2), Eigen::Vector3f((a + b + c) / 3)}) {
      points.push_back(p);
      directions.push_back(normals[f]);
    }
  }
  const std::vector<float> distance = DistanceAlong(surface, points, directions, reach_m);
  std::vector<char> marked(nf, 0);
  size_t count = 0;
  for (size_t f = 0; f < nf; ++f) {
    if (also && (*also)[f]) marked[f] = 1;
    for (int k = 0; k < 4; ++k) {
      const float d = distance[4 * f + k];
      if (std::isfinite(d) && std::abs(d) > tolerance_m) marked[f] = 1;
    }
    count += marked[f];
  }
  if (subdivided) *subdivided = count;
  if (count == 0) return mesh;
  const size_t first_new = mesh.num_vertices();
  TriangleMesh out = SubdivideMarked(mesh, marked);
  const std::vector<Eigen::Vector3f> vertex_normals = VertexNormals(out);
  const std::vector<Eigen::Vector3f> fresh(out.vertices.begin() + long(first_new), out.vertices.end());
  const std::vector<Eigen::Vector3f> fresh_normals(vertex_normals.begin() + long(first_new),
                                                   vertex_normals.end());
  const std::vector<float> snap = DistanceAlong(surface, fresh, fresh_normals, reach_m);
  for (size_t i = 0; i < fresh.size(); ++i)
    if (std::isfinite(snap[i])) out.vertices[first_new + i] += snap[i] * fresh_normals[i];
  return out;
}

size_t SubdivideNearCreases(double tolerance_m, TriangleMesh* mesh) {
  const std::vector<char> subdivide = FacesToSubdivide(*mesh, tolerance_m);
  *mesh = SubdivideMarked(*mesh, subdivide);
  SortSpatially(mesh);
  return size_t(std::count(subdivide.begin(), subdivide.end(), 1));
}

}  // namespace satmesh
