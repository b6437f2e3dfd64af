#pragma once
// Virtual cameras (paper 3.2.4): RFM rays are nearly straight near the surface, so each
// pixel's ray is the line through its localisations at two heights. Rays are localised
// exactly on a sparse grid of pixels and interpolated bilinearly in between.
#include <Eigen/Core>
#include <vector>

#include "core/geo/local_frame.h"
#include "core/raycast/ray_scene.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

class VirtualCamera {
 public:
  VirtualCamera() = default;
  // Rays for a width x height image of `rpc_level`, between frame heights z_low < z_high.
  // Throws Error{kInvalidInput} if a grid pixel cannot be localised.
  VirtualCamera(const RpcModel& rpc_level, const LocalFrame& frame, int width, int height,
                double z_low, double z_high, int grid_px);

  // Interpolated ray of pixel (col, row) (GDAL convention: centre of pixel i is i+0.5):
  // origin on the upper plane, unit direction pointing down, t_far just past the lower plane.
  Ray PixelRay(double col, double row) const;
  // The ray from exact localisation (for checks).
  Ray ExactRay(double col, double row) const;
  // Unit viewing direction (towards the ground) at the image centre.
  Eigen::Vector3d CentralDirection() const;

  int width() const { return width_; }
  double z_high() const { return z_high_; }  // the rays' origins lie on this plane
  int height() const { return height_; }

 private:
  Eigen::Vector3d LocalizeLocal(double col, double row, double z) const;

  RpcModel rpc_;
  LocalFrame frame_;
  int width_ = 0, height_ = 0, grid_px_ = 1, nodes_x_ = 0, nodes_y_ = 0;
  double z_low_ = 0, z_high_ = 0;
  std::vector<Eigen::Vector3d> top_, bottom_;  // per grid node, frame coordinates
};

}  // namespace satmesh
