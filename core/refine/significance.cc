#include "core/refine/significance.h"

#include <Eigen/Cholesky>

#include <cmath>
#include <vector>

#include "core/common/error.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/mesh_resolution.h"

namespace satmesh {

Eigen::Vector3d RegisterToInitial(const std::vector<Eigen::Vector3f>& normals,
                                  const std::vector<double>& offsets,
                                  const std::vector<double>& sigmas, double prior_sigma_m) {
  SATMESH_CHECK(normals.size() == offsets.size() && sigmas.size() == offsets.size() &&
                    prior_sigma_m > 0,
                ErrorCode::kInvalidArgument,
                "RegisterToInitial: one normal, offset and sigma per vertex; prior sigma > 0");
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  // Cauchy from T = 0 (a shift of several sigmas still pulls), then Tukey's biweight (a
  // real change beyond 4 sigmas does not pull at all).
  constexpr int kCauchy = 8, kTukey = 4;
  for (int it = 0; it < kCauchy + kTukey; ++it) {
    const bool tukey = it >= kCauchy;
    Eigen::Matrix3d a = Eigen::Matrix3d::Identity() / (prior_sigma_m * prior_sigma_m);
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (size_t v = 0; v < offsets.size(); ++v) {
      const double s = sigmas[v];
      if (!(std::isfinite(s) && s > 0) || !std::isfinite(offsets[v])) continue;
      const Eigen::Vector3d n = normals[v].cast<double>();
      const double u = (offsets[v] - n.dot(t)) / s;  // residual in sigmas
      double w;
      if (!tukey) {
        w = 1 / (1 + u * u / 4);  // Cauchy, scale 2
      } else {
        const double q = u * u / 16;  // Tukey, c = 4
        w = q < 1 ? (1 - q) * (1 - q) : 0;
      }
      w /= s * s;
      a.noalias() += w * n * n.transpose();
      b.noalias() += w * offsets[v] * n;
    }
    t = a.ldlt().solve(b);
  }
  return t;
}

SignificanceStats KeepSignificantChanges(const TriangleMesh& initial, double k, double max_offset_m,
                                         bool hold_boundary_xy, bool register_to_initial,
                                         TriangleMesh* mesh) {
  SATMESH_CHECK((k > 0 || (k == 0 && register_to_initial)) && max_offset_m > 0,
                ErrorCode::kInvalidArgument,
                "KeepSignificantChanges: k must be > 0 (0 only with the registration), "
                "max_offset_m > 0");
  const size_t nv = mesh->vertices.size();
  SATMESH_CHECK(mesh->height_sigma.size() == nv, ErrorCode::kInvalidArgument,
                "KeepSignificantChanges: the mesh has no height sigma per vertex");
  SignificanceStats stats;
  if (nv == 0 || initial.faces.empty()) return stats;
  const RayScene scene(initial);
  std::vector<Eigen::Vector3f> normals = VertexNormals(*mesh);
  std::vector<char> held(nv, 0);  // border vertices that move vertically only
  if (hold_boundary_xy) {
    const VertexAdjacency adjacency = BuildVertexAdjacency(*mesh);
    for (size_t v = 0; v < nv; ++v)
      if (adjacency.is_boundary[v] && normals[v].squaredNorm() > 0) {
        normals[v] = Eigen::Vector3f(0, 0, normals[v].z() >= 0 ? 1.f : -1.f);
        held[v] = 1;
      }
  }
  // Each vertex's offset from the initial surface along its normal: x = x0 + d n, so the
  // initial surface at signed distance t along n means d = -t (NaN: none within reach).
  std::vector<double> offsets(nv);
  const auto measure_offsets = [&] {
    const std::vector<float> along = DistanceAlong(scene, mesh->vertices, normals, max_offset_m);
    for (size_t v = 0; v < nv; ++v) offsets[v] = -double(along[v]);  // NaN stays NaN
  };
  measure_offsets();
  const std::vector<double> sigmas(mesh->height_sigma.begin(), mesh->height_sigma.end());
  if (register_to_initial) {
    stats.registration_m = RegisterToInitial(normals, offsets, sigmas, max_offset_m);
    const Eigen::Vector3f t = stats.registration_m.cast<float>();
    // A held border vertex keeps its outline: the vertical part only.
    for (size_t v = 0; v < nv; ++v) mesh->vertices[v] -= held[v] ? Eigen::Vector3f(0, 0, t.z()) : t;
    measure_offsets();
  }
  const double k4 = k * k * k * k;
  double gain_sum = 0;
  for (size_t v = 0; v < nv; ++v) {
    const double d = offsets[v];
    if (std::isnan(d)) continue;
    const double sigma = sigmas[v];
    const double z = std::isfinite(sigma) && sigma > 0 ? d / sigma : 0.0;
    const double z4 = z * z * z * z;
    const double gain = k4 > 0 ? z4 / (z4 + k4) : 1.0;  // k = 0: the registration only
    mesh->vertices[v] -= float((1 - gain) * d) * normals[v];
    gain_sum += gain;
    ++stats.vertices;
  }
  if (stats.vertices > 0) stats.mean_gain = gain_sum / double(stats.vertices);
  return stats;
}

}  // namespace satmesh
