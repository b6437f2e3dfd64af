#include "core/refine/projection_grid.h"

#include <cmath>

namespace satmesh {

ProjectionGrid::ProjectionGrid(const RpcModel& rpc_level, const LocalFrame& frame,
                               const Eigen::Vector3d& box_min, const Eigen::Vector3d& box_max,
                               double spacing_xy_m, double spacing_z_m)
    : rpc_(rpc_level), frame_(frame), origin_(box_min),
      spacing_(spacing_xy_m, spacing_xy_m, spacing_z_m) {
  const Eigen::Vector3d extent = box_max - box_min;
  nx_ = int(std::ceil(extent.x() / spacing_.x())) + 1;
  ny_ = int(std::ceil(extent.y() / spacing_.y())) + 1;
  nz_ = int(std::ceil(extent.z() / spacing_.z())) + 1;
  nodes_.resize(size_t(nx_) * ny_ * nz_);
  for (int k = 0; k < nz_; ++k)
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const Eigen::Vector3d X = origin_ + Eigen::Vector3d(i, j, k).cwiseProduct(spacing_);
        nodes_[(size_t(k) * ny_ + j) * nx_ + i] = rpc_.PixelFromGeo(frame_.GeoFromLocal(X));
      }
}

Eigen::Vector2d ProjectionGrid::ExactPixelFromLocal(const Eigen::Vector3d& X,
                                                    Eigen::Matrix<double, 2, 3>* J) const {
  Eigen::Matrix<double, 2, 3> pixel_from_geo;
  const Eigen::Vector2d px = rpc_.PixelFromGeo(frame_.GeoFromLocal(X), &pixel_from_geo);
  *J = pixel_from_geo * frame_.GeoFromLocalScale().asDiagonal();
  return px;
}

Eigen::Vector2d ProjectionGrid::PixelFromLocal(const Eigen::Vector3d& X,
                                               Eigen::Matrix<double, 2, 3>* J) const {
  const Eigen::Vector3d g = (X - origin_).cwiseQuotient(spacing_);
  const int i = int(std::floor(g.x())), j = int(std::floor(g.y())), k = int(std::floor(g.z()));
  if (i < 0 || j < 0 || k < 0 || i >= nx_ - 1 || j >= ny_ - 1 || k >= nz_ - 1)
    return ExactPixelFromLocal(X, J);
  const double fx = g.x() - i, fy = g.y() - j, fz = g.z() - k;
  const size_t sx = 1, sy = size_t(nx_), sz = size_t(nx_) * ny_;
  const size_t base = k * sz + j * sy + i;
  const Eigen::Vector2d &c000 = nodes_[base], &c100 = nodes_[base + sx],
                        &c010 = nodes_[base + sy], &c110 = nodes_[base + sy + sx],
                        &c001 = nodes_[base + sz], &c101 = nodes_[base + sz + sx],
                        &c011 = nodes_[base + sz + sy], &c111 = nodes_[base + sz + sy + sx];
  // Interpolate along x, then y, then z, keeping the partial derivatives.
  const Eigen::Vector2d c00 = c000 + fx * (c100 - c000), c10 = c010 + fx * (c110 - c010);
  const Eigen::Vector2d c01 = c001 + fx * (c101 - c001), c11 = c011 + fx * (c111 - c011);
  const Eigen::Vector2d c0 = c00 + fy * (c10 - c00), c1 = c01 + fy * (c11 - c01);
  const Eigen::Vector2d d00 = c100 - c000, d10 = c110 - c010, d01 = c101 - c001, d11 = c111 - c011;
  const Eigen::Vector2d dx0 = d00 + fy * (d10 - d00), dx1 = d01 + fy * (d11 - d01);
  J->col(0) = (dx0 + fz * (dx1 - dx0)) / spacing_.x();
  J->col(1) = ((c10 - c00) + fz * ((c11 - c01) - (c10 - c00))) / spacing_.y();
  J->col(2) = (c1 - c0) / spacing_.z();
  return c0 + fz * (c1 - c0);
}

}  // namespace satmesh
