#include "core/refine/virtual_camera.h"

#include <gtest/gtest.h>

#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

TEST(VirtualCamera, InterpolatedRaysMatchExactLocalisation) {
  const LocalFrame frame(Eigen::Vector3d(-81.66, 30.3, 10.0));
  RpcCoefficients c = testing::AffineRpc(frame, {25, 130}, 0.5, 400).coefficients();
  // Make the RFM genuinely non-linear (curved rays, varying scale).
  c.samp_num[7] = 2e-3;   // L²
  c.samp_num[9] = 1e-3;   // H²
  c.line_num[8] = -2e-3;  // P²
  c.line_num[6] = 1.5e-3; // PH
  c.samp_den[1] = 1e-3;
  const RpcModel rpc = RpcModel::FromCoefficients(c);
  const VirtualCamera camera(rpc, frame, 400, 400, -20, 40, 16);
  double max_error_px = 0;
  for (double row = 0.5; row < 400; row += 13.7) {
    for (double col = 0.5; col < 400; col += 11.3) {
      const Ray interp = camera.PixelRay(col, row), exact = camera.ExactRay(col, row);
      // Compare where the rays cross the ground (z = 0): the error in pixels of 0.5 m.
      auto at_ground = [](const Ray& r) {
        const double t = -r.origin.z() / r.direction.z();
        return (r.origin.cast<double>() + t * r.direction.cast<double>()).eval();
      };
      max_error_px = std::max(max_error_px, (at_ground(interp) - at_ground(exact)).norm() / 0.5);
    }
  }
  EXPECT_LT(max_error_px, 0.01);
  const Eigen::Vector3d d = camera.CentralDirection();
  EXPECT_NEAR(std::acos(-d.z()) * 180 / M_PI, 25.0, 1.0);  // off-nadir angle of the view
}

}  // namespace
}  // namespace satmesh
