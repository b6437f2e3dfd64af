#include "core/refine/significance.h"

#include <cmath>
#include <vector>

#include "core/common/error.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"

namespace satmesh {

SignificanceStats KeepSignificantChanges(const TriangleMesh& initial, double k, double max_offset_m,
                                         bool hold_boundary_xy, TriangleMesh* mesh) {
  SATMESH_CHECK(k > 0 && max_offset_m > 0, ErrorCode::kInvalidArgument,
                "KeepSignificantChanges: k and max_offset_m must be > 0");
  const size_t nv = mesh->vertices.size();
  SATMESH_CHECK(mesh->height_sigma.size() == nv, ErrorCode::kInvalidArgument,
                "KeepSignificantChanges: the mesh has no height sigma per vertex");
  SignificanceStats stats;
  if (nv == 0 || initial.faces.empty()) return stats;
  const RayScene scene(initial);
  std::vector<Eigen::Vector3f> normals = VertexNormals(*mesh);
  if (hold_boundary_xy) {
    const VertexAdjacency adjacency = BuildVertexAdjacency(*mesh);
    for (size_t v = 0; v < nv; ++v)
      if (adjacency.is_boundary[v] && normals[v].squaredNorm() > 0)
        normals[v] = Eigen::Vector3f(0, 0, normals[v].z() >= 0 ? 1.f : -1.f);
  }
  std::vector<Ray> rays(2 * nv);
  for (size_t v = 0; v < nv; ++v) {
    const float reach = normals[v].squaredNorm() > 0 ? float(max_offset_m) : 0.f;  // none: no hit
    rays[2 * v] = Ray{mesh->vertices[v], normals[v], 0.f, reach};
    rays[2 * v + 1] = Ray{mesh->vertices[v], -normals[v], 0.f, reach};
  }
  std::vector<RayHit> hits(2 * nv);
  scene.Intersect(rays.data(), hits.data(), rays.size());
  const double k4 = k * k * k * k;
  double gain_sum = 0;
  for (size_t v = 0; v < nv; ++v) {
    const RayHit& ahead = hits[2 * v];
    const RayHit& behind = hits[2 * v + 1];
    // x = x0 + d n: the initial surface ahead at t means x0 = x + t n, so d = -t.
    double d;
    if (ahead.hit() && (!behind.hit() || ahead.t <= behind.t)) d = -ahead.t;
    else if (behind.hit()) d = behind.t;
    else continue;
    const double sigma = mesh->height_sigma[v];
    const double z = std::isfinite(sigma) && sigma > 0 ? d / sigma : 0.0;
    const double z4 = z * z * z * z;
    const double gain = z4 / (z4 + k4);
    mesh->vertices[v] -= float((1 - gain) * d) * normals[v];
    gain_sum += gain;
    ++stats.vertices;
  }
  if (stats.vertices > 0) stats.mean_gain = gain_sum / double(stats.vertices);
  return stats;
}

}  // namespace satmesh
