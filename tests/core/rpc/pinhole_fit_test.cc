#include "core/rpc/pinhole_fit.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>

#include "core/common/error.h"
#include "core/geo/local_frame.h"
#include "tests/core/rpc/test_cameras.h"

namespace satmesh {
namespace {

TEST(PinholeFitOptions, DefaultsAreValid) { EXPECT_EQ(PinholeFitOptions{}.Check(), ""); }

TEST(PinholeFitOptions, InvalidFieldsAreNamed) {
  PinholeFitOptions o;
  o.grid_xy = 1;
  EXPECT_NE(o.Check().find("grid_xy"), std::string::npos);
  o = {};
  o.grid_z = 1;
  EXPECT_NE(o.Check().find("grid_z"), std::string::npos);
  o = {};
  o.max_iterations = -1;
  EXPECT_NE(o.Check().find("max_iterations"), std::string::npos);
}

TEST(FitPinhole, RejectsEmptyBox) {
  const auto camera = [](const Eigen::Vector3d& x) { return Eigen::Vector2d(x.x(), x.y()); };
  EXPECT_THROW(FitPinhole(camera, {0, 0, 0}, {1, 1, 0}), Error);
}

TEST(FitPinhole, RecoversAnExactPinhole) {
  // A far, tilted camera (600 km, 20 degrees off nadir) with non-square pixels.
  PinholeCamera truth;
  truth.fx = 2.0e6, truth.fy = 2.1e6, truth.cx = 512.5, truth.cy = -300;
  truth.cam_from_local_rotation = (Eigen::AngleAxisd(3.0, Eigen::Vector3d::UnitX()) *
                                   Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY()))
                                      .toRotationMatrix();
  truth.cam_from_local_translation = Eigen::Vector3d(10, -20, 6.0e5);
  const auto camera = [&](const Eigen::Vector3d& x) { return truth.PixelFromLocal(x); };
  const PinholeFitResult fit = FitPinhole(camera, {-150, -150, -20}, {150, 150, 40});
  EXPECT_LT(fit.max_px, 1e-6);
  EXPECT_LT(fit.max_px_half_step, 1e-6);
  EXPECT_NEAR(fit.dlt_skew_px, 0, 1e-6 * truth.fx);
  // Far away, only fx / distance is determined well; the image of the box is.
  EXPECT_NEAR(fit.camera.fx / fit.camera.fy, truth.fx / truth.fy, 1e-6);
}

// The satellite pushbroom views of the synthetic scenes (test_cameras.h), as RPCs, over
// a 300 x 300 x 60 m box in the refinement's local frame: a pinhole within 0.1 px.
TEST(FitPinhole, SatelliteRpcOverTheAoiWithinATenthOfAPixel) {
  const double zeniths[] = {5, 20, 35, 30};
  const double azimuths[] = {100, 10, 235, 300};
  const double gsds[] = {0.3, 0.4, 0.5, 0.3};
  for (int i = 0; i < 4; ++i) {
    test::PushbroomParams params;
    params.zenith_deg = zeniths[i], params.azimuth_deg = azimuths[i], params.gsd_m = gsds[i];
    const RpcModel rpc = test::FitPushbroom(params).model;
    const LocalFrame frame(params.center_lon_lat_h + Eigen::Vector3d(0, 0, 20));
    const auto pixel_from_local = [&](const Eigen::Vector3d& x) {
      return rpc.PixelFromGeo(frame.GeoFromLocal(x));
    };
    const PinholeFitResult fit = FitPinhole(pixel_from_local, {-150, -150, -20}, {150, 150, 40});
    std::printf(
        "zenith %.0f deg, %.1f m: DLT skew %.1f px, rms %.4f px; pinhole rms %.4f px, "
        "max %.4f px, half-step max %.4f px, %d iterations\n",
        zeniths[i], gsds[i], fit.dlt_skew_px, fit.dlt_rms_px, fit.rms_px, fit.max_px,
        fit.max_px_half_step, fit.iterations);
    EXPECT_LT(fit.max_px, 0.1) << "zenith " << zeniths[i];
    EXPECT_LT(fit.max_px_half_step, 0.1) << "zenith " << zeniths[i];
    EXPECT_GT(fit.camera.CenterInLocal().z(), 4e5);  // the satellite, hundreds of km up
  }
}

}  // namespace
}  // namespace satmesh
