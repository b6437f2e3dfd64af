#include "core/refine/sunlight.h"

#include <cmath>

#include "core/raycast/ray_scene.h"

namespace satmesh {

Eigen::Vector3f SunDirection(const AcquisitionInfo& acquisition) {
  if (!acquisition.sun_elevation_deg || !acquisition.sun_azimuth_deg) return Eigen::Vector3f::Zero();
  const double el = *acquisition.sun_elevation_deg * M_PI / 180;
  const double az = *acquisition.sun_azimuth_deg * M_PI / 180;
  if (!(el > 0)) return Eigen::Vector3f::Zero();
  return Eigen::Vector3d(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el))
      .cast<float>();
}

void MarkSunlight(const TriangleMesh& mesh, const std::vector<Eigen::Vector3f>& face_normals,
                  const std::vector<Eigen::Vector3f>& sun_directions,
                  const std::vector<std::pair<int, int>>& pairs, std::vector<ViewLevel>* views) {
  const RayScene scene(mesh);
  std::vector<Ray> rays;
  std::vector<RayHit> hits;
  for (ViewLevel& view : *views) {
    const std::vector<SurfacePoint>& surface = view.hit_map.surface;
    const size_t n = surface.size();
    std::vector<uint64_t>& sunlit = view.hit_map.sunlit;
    sunlit.assign(n, 0);
    view.hit_map.suns_marked = 0;
    rays.resize(n);
    hits.resize(n);
    uint64_t needed = view.view < 64 ? uint64_t(1) << view.view : 0;
    for (const auto& [i, j] : pairs) {
      if (i == view.view && j < 64) needed |= uint64_t(1) << j;
      if (j == view.view && i < 64) needed |= uint64_t(1) << i;
    }
    for (size_t s = 0; s < std::min<size_t>(64, sun_directions.size()); ++s) {
      const Eigen::Vector3f& sun = sun_directions[s];
      if (sun.squaredNorm() == 0 || !((needed >> s) & 1)) continue;
#pragma omp parallel for schedule(static)
      for (long p = 0; p < long(n); ++p) {
        const SurfacePoint& x = surface[p];
        if (x.face < 0) {
          rays[p] = Ray{Eigen::Vector3f::Zero(), sun, 0.f, 0.f};  // nothing to trace
          continue;
        }
        // Off the surface by 5 cm along its normal (towards the sun's side), so the ray
        // does not hit its own face.
        Eigen::Vector3f normal = face_normals[x.face];
        if (normal.dot(sun) < 0) normal = -normal;
        rays[p] = Ray{x.point + 0.05f * normal, sun, 0.f, 1e4f};
      }
      scene.Intersect(rays.data(), hits.data(), n);
      const uint64_t bit = uint64_t(1) << s;
      view.hit_map.suns_marked |= bit;
      for (size_t p = 0; p < n; ++p) {
        if (surface[p].face < 0) continue;
        // A face turned away from the sun is in its own shadow.
        const bool facing = face_normals[surface[p].face].dot(sun) > 0;
        if (facing && !hits[p].hit()) sunlit[p] |= bit;
      }
    }
  }
}

}  // namespace satmesh
