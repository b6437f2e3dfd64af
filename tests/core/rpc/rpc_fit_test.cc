#include "core/rpc/rpc_fit.h"

#include <gtest/gtest.h>

#include "core/common/error.h"
#include "tests/core/rpc/test_cameras.h"

namespace satmesh {
namespace {

TEST(RpcFitOptions, DefaultsAreValid) { EXPECT_EQ(RpcFitOptions{}.Check(), ""); }

TEST(RpcFitOptions, InvalidFieldsAreNamed) {
  RpcFitOptions o;
  o.grid_xy = 2;
  EXPECT_NE(o.Check().find("grid_xy"), std::string::npos);
  o = {};
  o.grid_h = 1;
  EXPECT_NE(o.Check().find("grid_h"), std::string::npos);
  o = {};
  o.regularization = -1;
  EXPECT_NE(o.Check().find("regularization"), std::string::npos);
  o = {};
  o.reweight_iterations = -1;
  EXPECT_NE(o.Check().find("reweight_iterations"), std::string::npos);
}

TEST(FitRpc, RejectsEmptyBox) {
  auto camera = [](const Eigen::Vector3d& g) { return Eigen::Vector2d(g.x(), g.y()); };
  EXPECT_THROW(FitRpc(camera, {0, 0, 0}, {1, 1, 0}), Error);
}

TEST(FitRpc, ReproducesAnExactRpc) {
  // A camera that is itself an RPC00B is fitted to round-off.
  const RpcModel truth = test::FitPushbroom({}).model;
  Eigen::Vector3d lo, hi;
  test::PushbroomCamera({}).Box(&lo, &hi);
  const RpcFitResult fit =
      FitRpc([&](const Eigen::Vector3d& g) { return truth.PixelFromGeo(g); }, lo, hi);
  EXPECT_LT(fit.max_px_half_step, 1e-4);
}

// Pushbroom cameras off-nadir 5..35 degrees, 0.3-0.5 m GSD, 2000 px, heights 0..100 m.
TEST(FitRpc, PushbroomBelowHundredthPixel) {
  const double zeniths[] = {5, 20, 35};
  const double azimuths[] = {100, 10, 235};
  const double gsds[] = {0.3, 0.4, 0.5};
  for (int i = 0; i < 3; ++i) {
    test::PushbroomParams p;
    p.zenith_deg = zeniths[i], p.azimuth_deg = azimuths[i], p.gsd_m = gsds[i];
    const RpcFitResult fit = test::FitPushbroom(p);
    RecordProperty("max_px_half_step_" + std::to_string(i), std::to_string(fit.max_px_half_step));
    std::printf("zenith %.0f deg: rms %.2e px, max %.2e px, half-step max %.2e px\n", zeniths[i],
                fit.rms_px, fit.max_px, fit.max_px_half_step);
    EXPECT_LT(fit.max_px_half_step, 0.01) << "zenith " << zeniths[i];
    EXPECT_LT(fit.max_px, 0.01);
  }
}

}  // namespace
}  // namespace satmesh
