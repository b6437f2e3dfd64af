// Unit tests of the measurement helpers behind `satmesh bench` / `satmesh zncc`.
#include "client/bench_support.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/common/error.h"
#include "core/common/memory.h"

namespace satmesh::cli {
namespace {

TEST(ParsePairs, ParsesList) {
  const auto pairs = ParsePairs("0-2,1-2", 3);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0], std::make_pair(0, 2));
  EXPECT_EQ(pairs[1], std::make_pair(1, 2));
}

TEST(ParsePairs, RejectsMalformedAndOutOfRange) {
  EXPECT_THROW(ParsePairs("0-3", 3), Error);
  EXPECT_THROW(ParsePairs("1-1", 3), Error);
  EXPECT_THROW(ParsePairs("0+1", 3), Error);
  EXPECT_THROW(ParsePairs("0-1x", 3), Error);
  EXPECT_THROW(ParsePairs("", 3), Error);
}

// A nadir-looking affine RPC over the frame centre: col = cx + x/gsd, row = cy - y/gsd.
RpcModel NadirRpc(const LocalFrame& frame, double gsd_m, int size_px) {
  RpcCoefficients c;
  const Eigen::Vector3d center = frame.center_lon_lat_h();
  c.long_off = center.x(), c.lat_off = center.y(), c.height_off = center.z();
  c.long_scale = c.lat_scale = 0.001;
  c.height_scale = 50;
  c.samp_off = c.line_off = 0.5 * size_px - 0.5;
  c.samp_scale = c.line_scale = 0.5 * size_px;
  c.samp_num[1] = c.long_scale * frame.meters_per_degree_lon() / gsd_m / c.samp_scale;
  c.line_num[2] = -c.lat_scale * frame.meters_per_degree_lat() / gsd_m / c.line_scale;
  c.samp_num[3] = 0.1 * c.height_scale / gsd_m / c.samp_scale;  // slightly oblique
  c.samp_den[0] = c.line_den[0] = 1;
  return RpcModel::FromCoefficients(c);
}

TEST(TimeRaycast, CastsOneRayPerPixelOfEachView) {
  RefineInput input;
  input.frame = LocalFrame(Eigen::Vector3d(5.44, 43.26, 100));
  input.min_z = -5, input.max_z = 5;
  for (int v = 0; v < 2; ++v) {
    RefineView view;
    view.image = ImageF(40, 30, 1.f);
    view.rpc = NadirRpc(input.frame, 0.5, 40);
    input.views.push_back(view);
  }
  // A flat square of 100 m, far larger than the views' 20 m x 15 m footprint.
  TriangleMesh mesh;
  mesh.vertices = {{-50, -50, 0}, {50, -50, 0}, {50, 50, 0}, {-50, 50, 0}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}};
  const RaycastTiming t = TimeRaycast(input, mesh, {0, 1}, /*level=*/0, /*grid_px=*/8, /*repeats=*/2);
  EXPECT_EQ(t.num_rays, 2 * 40 * 30);
  EXPECT_DOUBLE_EQ(t.hit_fraction, 1.0);
  EXPECT_GE(t.intersect_s, 0.0);
  EXPECT_GE(t.hit_map_s, 0.0);
  // Level 1 halves both image sides (rounding up).
  EXPECT_EQ(TimeRaycast(input, mesh, {0}, 1, 8, 1).num_rays, 20 * 15);
}

TEST(ReadMachineInfo, DescribesThisMachine) {
  const MachineInfo info = ReadMachineInfo();
  EXPECT_GT(info.num_cpus, 0);
  EXPECT_GT(info.mem_total_gib, 0.0);
  EXPECT_GE(info.load_1m, 0.0);
  EXPECT_GT(PeakRssMb(), 0.0);
  EXPECT_GE(CpuSeconds(), 0.0);
}

}  // namespace
}  // namespace satmesh::cli
