#include "core/refine/view_level.h"

#include <utility>

namespace satmesh {

ViewLevel MakeViewLevel(int view, int level, ImageF image_level, const RpcModel& rpc_window,
                        const LocalFrame& frame, double z_low, double z_high, int grid_px) {
  ViewLevel out;
  out.view = view;
  out.level = level;
  out.image = std::move(image_level);
  out.rpc = rpc_window.AtLevel(level);
  out.camera = VirtualCamera(out.rpc, frame, out.image.width, out.image.height, z_low, z_high,
                             grid_px);
  const int w = out.image.width, h = out.image.height;
  out.rays.resize(size_t(w) * h);
#pragma omp parallel for schedule(static)
  for (int row = 0; row < h; ++row)
    for (int col = 0; col < w; ++col)
      out.rays[size_t(row) * w + col] = out.camera.PixelRay(col + 0.5, row + 0.5);
  return out;
}

void CastHitMap(const RayScene& scene, ViewLevel* view) {
  HitMap& map = view->hit_map;
  const size_t n = view->rays.size();
  map.hits.resize(n);
  map.points.resize(n);
  scene.Intersect(view->rays.data(), map.hits.data(), n);
#pragma omp parallel for schedule(static)
  for (long i = 0; i < long(n); ++i) {
    if (map.hits[i].hit()) map.points[i] = view->rays[i].origin + map.hits[i].t * view->rays[i].direction;
  }
}

}  // namespace satmesh
