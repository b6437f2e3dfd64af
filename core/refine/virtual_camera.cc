#include "core/refine/virtual_camera.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/common/error.h"

namespace satmesh {

VirtualCamera::VirtualCamera(const RpcModel& rpc_level, const LocalFrame& frame, int width,
                             int height, double z_low, double z_high, int grid_px)
    : rpc_(rpc_level), frame_(frame), width_(width), height_(height),
      grid_px_(std::max(1, grid_px)), z_low_(z_low), z_high_(z_high) {
  SATMESH_CHECK(width > 0 && height > 0 && z_high > z_low, ErrorCode::kInvalidArgument,
                "VirtualCamera: empty image or height range");
  nodes_x_ = (width - 1) / grid_px_ + 2;
  nodes_y_ = (height - 1) / grid_px_ + 2;
  top_.resize(size_t(nodes_x_) * nodes_y_);
  bottom_.resize(top_.size());
  for (int ny = 0; ny < nodes_y_; ++ny) {
    for (int nx = 0; nx < nodes_x_; ++nx) {
      const double col = nx * grid_px_ + 0.5, row = ny * grid_px_ + 0.5;
      top_[size_t(ny) * nodes_x_ + nx] = LocalizeLocal(col, row, z_high_);
      bottom_[size_t(ny) * nodes_x_ + nx] = LocalizeLocal(col, row, z_low_);
    }
  }
}

Eigen::Vector3d VirtualCamera::LocalizeLocal(double col, double row, double z) const {
  const double h = frame_.center_lon_lat_h().z() + z;
  auto lon_lat = rpc_.LocalizeLonLat(Eigen::Vector2d(col, row), h);
  SATMESH_CHECK(lon_lat.has_value(), ErrorCode::kInvalidInput,
                "virtual camera: RPC localisation failed at pixel (" + std::to_string(col) +
                    ", " + std::to_string(row) + "), height " + std::to_string(h));
  return frame_.LocalFromGeo(Eigen::Vector3d(lon_lat->x(), lon_lat->y(), h));
}

namespace {
Ray RayThrough(const Eigen::Vector3d& top, const Eigen::Vector3d& bottom) {
  const Eigen::Vector3d d = bottom - top;
  const double length = d.norm();
  Ray ray;
  ray.origin = top.cast<float>();
  ray.direction = (d / length).cast<float>();
  ray.t_near = 0.f;
  ray.t_far = float(length * 1.05);
  return ray;
}
}  // namespace

Ray VirtualCamera::PixelRay(double col, double row) const {
  const double gx = std::clamp((col - 0.5) / grid_px_, 0.0, double(nodes_x_ - 1) - 1e-9);
  const double gy = std::clamp((row - 0.5) / grid_px_, 0.0, double(nodes_y_ - 1) - 1e-9);
  const int ix = int(gx), iy = int(gy);
  const double fx = gx - ix, fy = gy - iy;
  auto lerp = [&](const std::vector<Eigen::Vector3d>& g) {
    const size_t i00 = size_t(iy) * nodes_x_ + ix;
    return (1 - fy) * ((1 - fx) * g[i00] + fx * g[i00 + 1]) +
           fy * ((1 - fx) * g[i00 + nodes_x_] + fx * g[i00 + nodes_x_ + 1]);
  };
  return RayThrough(lerp(top_), lerp(bottom_));
}

Ray VirtualCamera::ExactRay(double col, double row) const {
  return RayThrough(LocalizeLocal(col, row, z_high_), LocalizeLocal(col, row, z_low_));
}

Eigen::Vector3d VirtualCamera::CentralDirection() const {
  const Ray r = PixelRay(0.5 * width_, 0.5 * height_);
  return r.direction.cast<double>().normalized();
}

}  // namespace satmesh
