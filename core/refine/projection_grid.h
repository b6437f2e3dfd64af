#pragma once
// Fast RFM projection for the refinement's inner loop: pixel coordinates of a view (at
// one level) tabulated on a 3D lattice of the local frame and interpolated trilinearly.
// The RFM is smooth at the lattice scale (second derivatives ~1e-5 px/m²), so the
// interpolation error stays far below 1e-3 px (checked in a test against the exact RPC);
// the Jacobian is the exact derivative of the interpolant. Points outside the lattice
// fall back to the exact RPC.
#include <Eigen/Core>
#include <vector>

#include "core/geo/local_frame.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

class ProjectionGrid {
 public:
  ProjectionGrid() = default;
  // Lattice over [box_min, box_max] (frame metres) with the given node spacings.
  ProjectionGrid(const RpcModel& rpc_level, const LocalFrame& frame, const Eigen::Vector3d& box_min,
                 const Eigen::Vector3d& box_max, double spacing_xy_m, double spacing_z_m);

  // Pixel (col, row) of frame point X and d(col,row)/d(x,y,z).
  Eigen::Vector2d PixelFromLocal(const Eigen::Vector3d& X,
                                 Eigen::Matrix<double, 2, 3>* pixel_from_local) const;

 private:
  Eigen::Vector2d ExactPixelFromLocal(const Eigen::Vector3d& X,
                                      Eigen::Matrix<double, 2, 3>* pixel_from_local) const;

  RpcModel rpc_;
  LocalFrame frame_;
  Eigen::Vector3d origin_{0, 0, 0}, spacing_{1, 1, 1};
  int nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<Eigen::Vector2d> nodes_;  // pixel at each lattice node, x fastest
};

}  // namespace satmesh
