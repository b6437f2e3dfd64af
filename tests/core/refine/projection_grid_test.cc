#include "core/refine/projection_grid.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/rpc/rpc_io.h"
#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

// Max pixel error of the lattice vs the exact RPC, and max relative Jacobian error.
std::pair<double, double> LatticeErrors(const RpcModel& rpc, const LocalFrame& frame) {
  const Eigen::Vector3d lo(-200, -200, -30), hi(200, 200, 60);
  const ProjectionGrid grid(rpc, frame, lo, hi, 16.0, 8.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  double max_px = 0, max_rel_jacobian = 0;
  for (int n = 0; n < 2000; ++n) {
    const Eigen::Vector3d X = lo + (hi - lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    Eigen::Matrix<double, 2, 3> J, J_geo;
    const Eigen::Vector2d px = grid.PixelFromLocal(X, &J);
    const Eigen::Vector2d exact = rpc.PixelFromGeo(frame.GeoFromLocal(X), &J_geo);
    const Eigen::Matrix<double, 2, 3> J_exact = J_geo * frame.GeoFromLocalScale().asDiagonal();
    max_px = std::max(max_px, (px - exact).norm());
    max_rel_jacobian = std::max(max_rel_jacobian, (J - J_exact).norm() / J_exact.norm());
  }
  return {max_px, max_rel_jacobian};
}

TEST(ProjectionGrid, MatchesExactRpcOnCurvedModel) {
  const LocalFrame frame(Eigen::Vector3d(-81.66, 30.3, 10.0));
  RpcCoefficients c = testing::AffineRpc(frame, {25, 130}, 0.3, 2000).coefficients();
  c.long_scale = c.lat_scale = 0.01;  // ~1 km normalisation, curvature like a real RPC
  c.samp_num[7] = 2e-4;
  c.line_num[8] = -2e-4;
  c.line_num[6] = 1e-4;
  c.samp_den[1] = 1e-4;
  const auto [max_px, max_rel_jacobian] = LatticeErrors(RpcModel::FromCoefficients(c), frame);
  EXPECT_LT(max_px, 1e-3);
  EXPECT_LT(max_rel_jacobian, 1e-3);
}

TEST(ProjectionGrid, MatchesExactRpcOnPleiades) {
  const std::string path = std::string(SATMESH_SHARED_DATA_DIR) + "/pleiades_marseille_triplet/img_01.tif";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path;
  const RpcModel rpc = ReadRpc(path);
  const Eigen::Vector3d center(rpc.coefficients().long_off, rpc.coefficients().lat_off,
                               rpc.coefficients().height_off);
  const auto [max_px, max_rel_jacobian] = LatticeErrors(rpc, LocalFrame(center));
  EXPECT_LT(max_px, 1e-3);
  EXPECT_LT(max_rel_jacobian, 1e-3);
}

}  // namespace
}  // namespace satmesh
