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
  float_cells_.resize(cells_.size());
  for (size_t c = 0; c < cells_.size(); ++c) {
    FloatCell& f = float_cells_[c];
    for (int r = 0; r < 2; ++r) {
      f.pixel[r] = float(cells_[c].pixel[r]);
      for (int k = 0; k < 3; ++k) f.jacobian[3 * r + k] = float(cells_[c].pixel_from_local(r, k));
    }
  }
}

ProjectionGrid::FloatLattice ProjectionGrid::float_lattice() const {
  FloatLattice l;
  l.cells = float_cells_.data();
  for (int a = 0; a < 3; ++a) {
    l.origin[a] = float(origin_[a]);
    l.inv_spacing[a] = float(inv_spacing_[a]);
    l.spacing[a] = float(spacing_[a]);
  }
  l.n[0] = nx_, l.n[1] = ny_, l.n[2] = nz_;
  return l;
}

Eigen::Vector2d ProjectionGrid::ExactPixelFromLocal(const Eigen::Vector3d& X,
                                                    Eigen::Matrix<double, 2, 3>* J) const {
  Eigen::Matrix<double, 2, 3> pixel_from_geo;
  const Eigen::Vector2d px = rpc_.PixelFromGeo(frame_.GeoFromLocal(X), &pixel_from_geo);
  *J = pixel_from_geo * frame_.GeoFromLocalScale().asDiagonal();
  return px;
}

}  // namespace satmesh
