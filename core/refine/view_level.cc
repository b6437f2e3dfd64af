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
  out.rays.resize(size_t(w) * h);
#pragma omp parallel for schedule(static)
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      out.rays[size_t(row) * w + col] = out.camera.PixelRay(col + 0.5, row + 0.5);
  return out;
}

double CastHitMap(const RayScene& scene, ViewLevel* view) {
  HitMap& map = view->hit_map;
  const size_t n = view->rays.size();
  map.hits.resize(n);
  map.points.resize(n);
  map.faces.resize(n);
  const auto start = std::chrono::steady_clock::now();
  scene.IntersectImage(view->rays.data(), view->width(), view->height(), map.hits.data());
  const double intersect_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
#pragma omp parallel for schedule(static)
  for (long i = 0; i < long(n); ++i) {
    map.faces[i] = map.hits[i].face;
    if (map.hits[i].hit()) map.points[i] = view->rays[i].origin + map.hits[i].t * view->rays[i].direction;
  }
  return intersect_s;
}

void SetRayCosines(const std::vector<Eigen::Vector3f>& face_normals, ViewLevel* view) {
  HitMap& map = view->hit_map;
  map.ray_cos.resize(map.hits.size());
#pragma omp parallel for schedule(static)
  for (long p = 0; p < long(map.hits.size()); ++p) {
    const int face = map.hits[p].face;
    map.ray_cos[p] = face >= 0 ? view->rays[p].direction.dot(face_normals[face]) : 0.f;
  }
}

namespace {

// Ray-plane intersection with triangle (p0, p1, p2) (Möller-Trumbore, no bounds test):
// t and the barycentrics (u, v) of Embree's convention. False if the ray is parallel.
inline bool IntersectTrianglePlane(const Ray& ray, const Eigen::Vector3f& p0,
                                   const Eigen::Vector3f& p1, const Eigen::Vector3f& p2,
                                   float* t, float* u, float* v) {
  const Eigen::Vector3f e1 = p1 - p0, e2 = p2 - p0;
  const Eigen::Vector3f pvec = ray.direction.cross(e2);
  const float det = e1.dot(pvec);
  if (std::abs(det) < 1e-12f) return false;
  const float inv_det = 1.f / det;
  const Eigen::Vector3f tvec = ray.origin - p0;
  *u = tvec.dot(pvec) * inv_det;
  const Eigen::Vector3f qvec = tvec.cross(e1);
  *v = ray.direction.dot(qvec) * inv_det;
  *t = e2.dot(qvec) * inv_det;
  return true;
}

// True where a 4-neighbour missed or its depth differs by more than jump (occlusion edge).
inline bool AtDepthEdge(const std::vector<RayHit>& hits, int w, int h, int col, int row,
                        float jump) {
  const float t = hits[size_t(row) * w + col].t;
  const int dc[4] = {-1, 1, 0, 0}, dr[4] = {0, 0, -1, 1};
  for (int k = 0; k < 4; ++k) {
    const int c = col + dc[k], r = row + dr[k];
    if (c < 0 || r < 0 || c >= w || r >= h) continue;
    const RayHit& n = hits[size_t(r) * w + c];
    if (!n.hit() || std::abs(n.t - t) > jump) return true;
  }
  return false;
}

}  // namespace

HitMapUpdate UpdateHitMap(const RayScene& scene, const TriangleMesh& mesh, float edge_tolerance,
                          float depth_jump_m, ViewLevel* view) {
  HitMap& map = view->hit_map;
  const int w = view->width(), h = view->height();
  const float lo = -edge_tolerance, hi = 1.f + edge_tolerance;
  std::vector<uint8_t> edge(map.hits.size(), 0);
#pragma omp parallel for schedule(static)
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      if (map.hits[size_t(row) * w + col].hit())
        edge[size_t(row) * w + col] = AtDepthEdge(map.hits, w, h, col, row, depth_jump_m);

  std::vector<uint32_t> recast;
  long kept = 0;
#pragma omp parallel
  {
    std::vector<uint32_t> local;
    long local_kept = 0;
#pragma omp for schedule(static) nowait
    for (long p = 0; p < long(map.hits.size()); ++p) {
      RayHit& hit = map.hits[p];
      if (!hit.hit()) continue;
      const Ray& ray = view->rays[p];
      const Eigen::Vector3i& f = mesh.faces[hit.face];
      float t, u, v;
      const bool ok = !edge[p] &&
                      IntersectTrianglePlane(ray, mesh.vertices[f[0]], mesh.vertices[f[1]],
                                             mesh.vertices[f[2]], &t, &u, &v) &&
                      u >= lo && v >= lo && u + v <= hi && t >= ray.t_near && t <= ray.t_far;
      if (!ok) {
        local.push_back(uint32_t(p));
        continue;
      }
      hit.t = t, hit.u = u, hit.v = v;
      map.points[p] = ray.origin + t * ray.direction;
      ++local_kept;
    }
#pragma omp critical
    {
      recast.insert(recast.end(), local.begin(), local.end());
      kept += local_kept;
    }
  }
  std::sort(recast.begin(), recast.end());  // row order: coherent packets
  std::vector<Ray> rays(recast.size());
  for (size_t k = 0; k < recast.size(); ++k) rays[k] = view->rays[recast[k]];
  std::vector<RayHit> hits(recast.size());
  const auto start = std::chrono::steady_clock::now();
  scene.Intersect(rays.data(), hits.data(), rays.size());
  HitMapUpdate update;
  update.intersect_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (size_t k = 0; k < recast.size(); ++k) {
    const uint32_t p = recast[k];
    map.hits[p] = hits[k];
    map.faces[p] = hits[k].face;
    if (hits[k].hit()) map.points[p] = rays[k].origin + hits[k].t * rays[k].direction;
  }
  update.kept = kept;
  update.recast = long(recast.size());
  return update;
}

}  // namespace satmesh
