#include "core/refine/significance.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/common/error.h"
#include "core/mesh/topology.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/mesh_resolution.h"

namespace satmesh {
namespace {

double SignificanceGain(double z, double k) {
  const double z4 = z * z * z * z, k4 = k * k * k * k;
  return z4 / (z4 + k4);
}

}  // namespace

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

std::vector<double> PooledSignificantOffsets(const TriangleMesh& mesh,
                                             const VertexAdjacency& adjacency,
                                             const std::vector<Eigen::Vector3f>& normals,
                                             const std::vector<double>& offsets,
                                             const std::vector<double>& sigmas, double radius_m,
                                             double floor_m, double k) {
  const size_t nv = mesh.vertices.size();
  SATMESH_CHECK(normals.size() == nv && offsets.size() == nv && sigmas.size() == nv &&
                    adjacency.neighbor_offsets.size() == nv + 1 && radius_m > 0 &&
                    floor_m >= 0 && k > 0,
                ErrorCode::kInvalidArgument,
                "PooledSignificantOffsets: one normal, offset and sigma per vertex, the mesh's "
                "adjacency; radius > 0, floor >= 0, k > 0");
  std::vector<char> counts(nv);
  for (size_t v = 0; v < nv; ++v)
    counts[v] = std::isfinite(offsets[v]) && std::isfinite(sigmas[v]) && sigmas[v] > 0;
  const float r2 = float(radius_m * radius_m);
  constexpr float kSameSurfaceCos = 0.8f;  // normals within 37 degrees
  constexpr double kTukeySigmas = 4;
  std::vector<double> kept(nv, 0.0);
#pragma omp parallel
  {
    std::vector<int> stamp(nv, -1);  // the vertex whose neighbourhood last reached it
    std::vector<int> queue;
    std::vector<double> values, kernels, inverse_variances, sorted;
#pragma omp for schedule(dynamic, 1024)
    for (long long vi = 0; vi < (long long)nv; ++vi) {
      const int v = int(vi);
      const Eigen::Vector3f n = normals[v];
      if (std::isnan(offsets[v]) || n.squaredNorm() == 0) continue;
      const Eigen::Vector3f p = mesh.vertices[v];
      queue.assign(1, v);
      values.clear();
      kernels.clear();
      inverse_variances.clear();
      stamp[v] = v;
      for (size_t qi = 0; qi < queue.size(); ++qi) {
        const int u = queue[qi];
        if (counts[u]) {
          const double q = 1 - double((mesh.vertices[u] - p).squaredNorm()) / double(r2);
          values.push_back(offsets[u]);
          kernels.push_back(q * q);
          inverse_variances.push_back(1 / (sigmas[u] * sigmas[u]));
        }
        for (int e = adjacency.neighbor_offsets[u]; e < adjacency.neighbor_offsets[u + 1]; ++e) {
          const int w = adjacency.neighbors[e];
          if (stamp[w] == v) continue;
          stamp[w] = v;
          if ((mesh.vertices[w] - p).squaredNorm() < r2 && normals[w].dot(n) >= kSameSurfaceCos)
            queue.push_back(w);
        }
      }
      if (values.empty()) continue;
      sorted = values;
      std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
      double mean = sorted[sorted.size() / 2];
      double sum_w = 0, sum_w2s2 = 0;
      for (int it = 0; it < 3; ++it) {
        double sum_wd = 0;
        sum_w = sum_w2s2 = 0;
        for (size_t i = 0; i < values.size(); ++i) {
          const double e = values[i] - mean;
          const double t = e * e * inverse_variances[i] / (kTukeySigmas * kTukeySigmas);
          if (t >= 1) continue;
          const double w = kernels[i] * (1 - t) * (1 - t) * inverse_variances[i];
          sum_w += w;
          sum_wd += w * values[i];
          sum_w2s2 += w * w / inverse_variances[i];
        }
        if (!(sum_w > 0)) break;
        mean = sum_wd / sum_w;
      }
      if (!(sum_w > 0)) continue;
      const double sigma = std::sqrt(sum_w2s2 / (sum_w * sum_w) + floor_m * floor_m);
      kept[v] = SignificanceGain(mean / sigma, k) * mean;
    }
  }
  return kept;
}

SignificanceStats KeepSignificantChanges(const TriangleMesh& initial,
                                         const SignificanceOptions& options, TriangleMesh* mesh) {
  const double k = options.k, max_offset_m = options.max_offset_m;
  const bool hold_boundary_xy = options.hold_boundary_xy;
  const bool register_to_initial = options.register_to_initial;
  SATMESH_CHECK((k > 0 || (k == 0 && register_to_initial)) && max_offset_m > 0 &&
                    options.scales >= 0 && (options.scales == 0 || options.gsd_m > 0) &&
                    options.floor_gsd >= 0,
                ErrorCode::kInvalidArgument,
                "KeepSignificantChanges: k must be > 0 (0 only with the registration), "
                "max_offset_m > 0, scales >= 0 (> 0: a GSD > 0), floor >= 0");
  const size_t nv = mesh->vertices.size();
  SATMESH_CHECK(mesh->height_sigma.size() == nv, ErrorCode::kInvalidArgument,
                "KeepSignificantChanges: the mesh has no height sigma per vertex");
  SignificanceStats stats;
  if (nv == 0 || initial.faces.empty()) return stats;
  const RayScene scene(initial);
  std::vector<Eigen::Vector3f> normals = VertexNormals(*mesh);
  std::vector<char> held(nv, 0);  // border vertices that move vertically only
  const bool pools = k > 0 && options.scales > 0;
  // Built once: the border below and every radius of the pooled tests walk it.
  const VertexAdjacency adjacency =
      hold_boundary_xy || pools ? BuildVertexAdjacency(*mesh) : VertexAdjacency{};
  if (hold_boundary_xy) {
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
  // Coarse to fine: each radius keeps what is coherent in what the coarser ones left.
  std::vector<double> pooled(nv, 0.0), residual = offsets;
  if (pools) {
    for (int i = options.scales - 1; i >= 0; --i) {
      const double radius_m = 8 * std::ldexp(1.0, i) * options.gsd_m;
      const std::vector<double> kept =
          PooledSignificantOffsets(*mesh, adjacency, normals, residual, sigmas, radius_m,
                                   options.floor_gsd * options.gsd_m, k);
      for (size_t v = 0; v < nv; ++v) {
        pooled[v] += kept[v];
        residual[v] -= kept[v];
      }
    }
  }
  double gain_sum = 0, pooled_sum = 0;
  for (size_t v = 0; v < nv; ++v) {
    const double d = offsets[v];
    if (std::isnan(d)) continue;
    const double sigma = sigmas[v];
    const bool seen = std::isfinite(sigma) && sigma > 0;
    const double r = residual[v];
    const double z = seen ? r / sigma : 0.0;
    const double gain = k > 0 ? SignificanceGain(z, k) : 1.0;  // k = 0: the registration only
    // Unseen: no pooled share either (k = 0 keeps everything).
    const double keep = k > 0 && !seen ? 0.0 : pooled[v] + gain * r;
    mesh->vertices[v] -= float(d - keep) * normals[v];
    if (d != 0) {
      gain_sum += std::clamp(keep / d, 0.0, 1.0);
      pooled_sum += std::clamp(pooled[v] / d, 0.0, 1.0);
    } else {
      gain_sum += 1;
    }
    ++stats.vertices;
  }
  if (stats.vertices > 0) {
    stats.mean_gain = gain_sum / double(stats.vertices);
    stats.pooled_share = pooled_sum / double(stats.vertices);
  }
  return stats;
}

}  // namespace satmesh
