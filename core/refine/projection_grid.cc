#include "core/refine/projection_grid.h"

#include <algorithm>
#include <cmath>

namespace satmesh {

ProjectionGrid::ProjectionGrid(const RpcModel& rpc_level, const LocalFrame& frame,
                               const Eigen::Vector3d& box_min, const Eigen::Vector3d& box_max,
                               double spacing_xy_m, double spacing_z_m)
    : rpc_(rpc_level), frame_(frame), origin_(box_min),
      spacing_(spacing_xy_m, spacing_xy_m, spacing_z_m),
      inv_spacing_(spacing_.cwiseInverse()) {
  const Eigen::Vector3d extent = box_max - box_min;
  nx_ = std::max(1, int(std::ceil(extent.x() / spacing_.x())));
  ny_ = std::max(1, int(std::ceil(extent.y() / spacing_.y())));
  nz_ = std::max(1, int(std::ceil(extent.z() / spacing_.z())));
  cells_.resize(size_t(nx_) * ny_ * nz_);
#pragma omp parallel for schedule(static)
  for (int k = 0; k < nz_; ++k)
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const Eigen::Vector3d centre =
            origin_ + (Eigen::Vector3d(i, j, k).array() + 0.5).matrix().cwiseProduct(spacing_);
        Cell& cell = cells_[(size_t(k) * ny_ + j) * nx_ + i];
        cell.pixel = ExactPixelFromLocal(centre, &cell.pixel_from_local);
      }
}

Eigen::Vector2d ProjectionGrid::ExactPixelFromLocal(const Eigen::Vector3d& X,
                                                    Eigen::Matrix<double, 2, 3>* J) const {
  Eigen::Matrix<double, 2, 3> pixel_from_geo;
  const Eigen::Vector2d px = rpc_.PixelFromGeo(frame_.GeoFromLocal(X), &pixel_from_geo);
  *J = pixel_from_geo * frame_.GeoFromLocalScale().asDiagonal();
  return px;
}

}  // namespace satmesh
