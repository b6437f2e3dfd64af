#include "core/refine/view_level.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <utility>

namespace satmesh {

void SurfaceBox(const TriangleMesh& mesh, double min_z, double max_z, Eigen::Vector3d* box_min,
                Eigen::Vector3d* box_max) {
  const double margin = 2.0 + 0.1 * (max_z - min_z);
  *box_min = Eigen::Vector3d::Constant(1e30);
  *box_max = -*box_min;
  for (const auto& p : mesh.vertices) {
    *box_min = box_min->cwiseMin(p.cast<double>());
    *box_max = box_max->cwiseMax(p.cast<double>());
  }
  *box_min -= Eigen::Vector3d(10, 10, 0);
  *box_max += Eigen::Vector3d(10, 10, 0);
  box_min->z() = std::min(box_min->z(), min_z) - margin;
  box_max->z() = std::max(box_max->z(), max_z) + margin;
}

ViewLevel MakeViewLevel(int view, int level, ImageF image_level, const RpcModel& rpc_window,
                        const LocalFrame& frame, const Eigen::Vector3d& box_min,
                        const Eigen::Vector3d& box_max, int grid_px) {
  const double z_low = box_min.z(), z_high = box_max.z();
  ViewLevel out;
  out.view = view;
  out.level = level;
  out.image = std::move(image_level);
  out.rpc = rpc_window.AtLevel(level);
  out.camera = VirtualCamera(out.rpc, frame, out.image.width, out.image.height, z_low, z_high,
                             grid_px);
  // Lattice spacing: the RFM is near-linear over tens of metres (see projection_grid.h).
  out.projection = ProjectionGrid(out.rpc, frame, box_min, box_max, /*spacing_xy_m=*/16.0,
                                  /*spacing_z_m=*/8.0);
  const int w = out.image.width, h = out.image.height;
  out.ray_directions.resize(size_t(w) * h);
#pragma omp parallel for schedule(static)
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      out.ray_directions[size_t(row) * w + col] = out.camera.PixelRay(col + 0.5, row + 0.5).direction;
  return out;
}

std::vector<Ray> PixelRays(const ViewLevel& view) {
  const int w = view.width(), h = view.height();
  std::vector<Ray> rays(size_t(w) * h);
#pragma omp parallel for schedule(static)
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col) rays[size_t(row) * w + col] = view.camera.PixelRay(col + 0.5, row + 0.5);
  return rays;
}

double CastHitMap(const RayScene& scene, ViewLevel* view,
                  const std::vector<Eigen::Vector3f>* face_normals) {
  HitMap& map = view->hit_map;
  const std::vector<Ray> rays = PixelRays(*view);
  const size_t n = rays.size();
  map.hits.resize(n);
  map.surface.resize(n);
  if (face_normals) map.ray_cos.resize(n);
  const auto start = std::chrono::steady_clock::now();
  scene.IntersectImage(rays.data(), view->width(), view->height(), map.hits.data());
  const double intersect_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
#pragma omp parallel for schedule(static)
  for (long i = 0; i < long(n); ++i) {
    const RayHit& hit = map.hits[i];
    map.surface[i].face = hit.face;
    if (hit.hit()) map.surface[i].point = rays[i].origin + hit.t * rays[i].direction;
    if (face_normals) map.ray_cos[i] = RayCosine(rays[i].direction, hit.face, *face_normals);
  }
  return intersect_s;
}

}  // namespace satmesh
