#include "core/refine/bias_estimation.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>

#include "core/common/error.h"
#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

const std::vector<std::pair<int, int>> kAllPairs = {{0, 1}, {0, 2}, {1, 2}};

// The textured plane seen by the default views; the initial surface is the true plane.
RefineInput PlaneInput() {
  const testing::Plane plane;
  return testing::MakePlaneInput(plane, testing::DefaultViews(),
                                 testing::PlaneMesh(plane, 40, 1.0, 0.0));
}

TEST(BiasOptions, DefaultsAreValid) { EXPECT_EQ(BiasOptions().Check(), ""); }

TEST(BiasOptions, InvalidValuesAreNamed) {
  BiasOptions o;
  o.search_radius_px = 0;
  EXPECT_NE(o.Check().find("search_radius_px"), std::string::npos);
  o = BiasOptions();
  o.refine.zncc_window_radius = 0;
  EXPECT_NE(o.Check().find("zncc_window_radius"), std::string::npos);
}

TEST(EstimateViewBiases, ZeroBiasStaysZero) {
  const BiasEstimate e = EstimateViewBiases(PlaneInput(), kAllPairs);
  EXPECT_EQ(e.reference_view, 0);  // every view is in two pairs: the first
  for (int v = 0; v < 3; ++v) {
    EXPECT_TRUE(e.solved[v]);
    EXPECT_LT(e.bias_col_row_px[v].norm(), 0.03) << "view " << v << ": " << e.bias_col_row_px[v].transpose();
  }
}

TEST(EstimateViewBiases, RecoversInjectedBias) {
  RefineInput input = PlaneInput();
  // The RPC of view 1 predicts pixels shifted by (2.7, -1.3): the correction is the opposite.
  const Eigen::Vector2d injected(2.7, -1.3);
  input.views[1].rpc = input.views[1].rpc.WithBias(injected);
  BiasOptions relative;  // the reference view's datum: the other views exactly corrected
  relative.minimum_norm_datum = false;
  const BiasEstimate e = EstimateViewBiases(input, kAllPairs, relative);
  EXPECT_NEAR(e.bias_col_row_px[1].x(), -injected.x(), 0.05);
  EXPECT_NEAR(e.bias_col_row_px[1].y(), -injected.y(), 0.05);
  EXPECT_LT(e.bias_col_row_px[2].norm(), 0.05) << e.bias_col_row_px[2].transpose();
  EXPECT_GT(e.zncc_after[1], e.zncc_before[1] + 0.1);

  ApplyViewBiases(e, &input);
  EXPECT_NEAR(input.views[1].rpc.bias().x(), 0.0, 0.05);
  EXPECT_NEAR(input.views[1].rpc.bias().y(), 0.0, 0.05);
}

TEST(EstimateViewBiases, ThreadsDoNotChangeTheEstimate) {
  // The shifts of a search step are evaluated in parallel, one per thread: the estimate
  // is the same as one thread's, bit for bit.
  RefineInput input = PlaneInput();
  input.views[1].rpc = input.views[1].rpc.WithBias({1.3, 0.6});
  input.views[2].rpc = input.views[2].rpc.WithBias({-0.8, 0.4});
  BiasOptions relative;
  relative.minimum_norm_datum = false;
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const BiasEstimate one = EstimateViewBiases(input, kAllPairs, relative);
  omp_set_num_threads(std::max(2, threads));
  const BiasEstimate many = EstimateViewBiases(input, kAllPairs, relative);
  omp_set_num_threads(threads);
  for (int v = 0; v < 3; ++v) {
    EXPECT_EQ(one.bias_col_row_px[v], many.bias_col_row_px[v]) << "view " << v;
    EXPECT_EQ(one.zncc_after[v], many.zncc_after[v]) << "view " << v;
  }
  EXPECT_NEAR(many.bias_col_row_px[1].x(), -1.3, 0.05);
  EXPECT_NEAR(many.bias_col_row_px[1].y(), -0.6, 0.05);
  EXPECT_NEAR(many.bias_col_row_px[2].x(), 0.8, 0.05);
  EXPECT_NEAR(many.bias_col_row_px[2].y(), -0.4, 0.05);
}

TEST(EstimateViewBiases, ReferenceViewIsHeldFixed) {
  RefineInput input = PlaneInput();
  input.views[0].rpc = input.views[0].rpc.WithBias({0.4, 0.6});
  BiasOptions options;
  options.reference_view = 2;
  options.minimum_norm_datum = false;
  const BiasEstimate e = EstimateViewBiases(input, {{0, 2}, {1, 2}}, options);
  EXPECT_EQ(e.bias_col_row_px[2], Eigen::Vector2d::Zero());
  EXPECT_NEAR(e.bias_col_row_px[0].x(), -0.4, 0.05);
  EXPECT_NEAR(e.bias_col_row_px[0].y(), -0.6, 0.05);
  EXPECT_LT(e.bias_col_row_px[1].norm(), 0.05);
}

// d(col,row)/d(east,north) of a view at a local point, by central differences (independent
// of MinimumNormDatum's analytic RPC Jacobian).
Eigen::Matrix2d PixelPerMetre(const RefineInput& input, int view, const Eigen::Vector3d& p) {
  Eigen::Matrix2d j;
  for (int axis = 0; axis < 2; ++axis) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[axis] = 0.5;
    const RpcModel& rpc = input.views[view].rpc;
    j.col(axis) = rpc.PixelFromGeo(input.frame.GeoFromLocal(p + d)) -
                  rpc.PixelFromGeo(input.frame.GeoFromLocal(p - d));
  }
  return j;  // per metre (the step is 1 m in all)
}

TEST(EstimateViewBiases, MinimumNormDatumMakesTheCorrectionsSmallest) {
  // Every view biased, as vendor RPCs are. The pairs see only the biases' differences; the
  // datum of minimum corrections is the least-squares ground shift t of the true
  // corrections -b_v: c_v = -b_v + J_v t, t = argmin sum |-b_v + J_v t|^2, whichever view
  // is the reference.
  RefineInput input = PlaneInput();
  const std::vector<Eigen::Vector2d> b = {{0.9, -1.2}, {-1.4, 0.3}, {0.6, 1.1}};
  for (int v = 0; v < 3; ++v) input.views[v].rpc = input.views[v].rpc.WithBias(b[v]);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : input.initial_mesh.vertices) centre += p.cast<double>();
  centre /= double(input.initial_mesh.vertices.size());
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  std::vector<Eigen::Matrix2d> j(3);
  for (int v = 0; v < 3; ++v) {
    j[v] = PixelPerMetre(input, v, centre);
    normal += j[v].transpose() * j[v];
    rhs += j[v].transpose() * -b[v];
  }
  const Eigen::Vector2d t = -normal.inverse() * rhs;
  for (int reference = 0; reference < 3; reference += 2) {
    BiasOptions options;
    options.reference_view = reference;
    const BiasEstimate e = EstimateViewBiases(input, kAllPairs, options);
    Eigen::Vector2d weighted = Eigen::Vector2d::Zero();
    for (int v = 0; v < 3; ++v) {
      const Eigen::Vector2d expected = -b[v] + j[v] * t;
      EXPECT_NEAR(e.bias_col_row_px[v].x(), expected.x(), 0.05) << "reference " << reference << " view " << v;
      EXPECT_NEAR(e.bias_col_row_px[v].y(), expected.y(), 0.05) << "reference " << reference << " view " << v;
      weighted += j[v].transpose() * e.bias_col_row_px[v];
    }
    // The normal equations' condition: no ground shift makes the corrections smaller.
    EXPECT_LT(weighted.norm(), 0.05 * j[0].norm()) << "reference " << reference;
    EXPECT_GT(e.datum_shift_m.norm(), 0.1);  // the reference's own bias was ~1.5 px
  }
}

TEST(EstimateViewBiases, UnpairedViewIsNotSolved) {
  const BiasEstimate e = EstimateViewBiases(PlaneInput(), {{0, 1}});
  EXPECT_TRUE(e.solved[1]);
  EXPECT_FALSE(e.solved[2]);
  EXPECT_EQ(e.bias_col_row_px[2], Eigen::Vector2d::Zero());
}

TEST(EstimateViewBiases, BadPairThrows) {
  EXPECT_THROW(EstimateViewBiases(PlaneInput(), {{0, 3}}), Error);
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

TEST(EstimateViewBiases, OnAFlatMeshTheDatumStaysAtMinimumCorrections) {
  // A mesh start (register_to_initial: on) over a plane: a common ground shift of the
  // block changes nothing the pairs can see, so the block stays at the datum of minimum
  // corrections rather than wandering with the objective's noise.
  RefineInput input = PlaneInput();
  input.initial_is_mesh = true;
  const std::vector<Eigen::Vector2d> b = {{1.4, -0.9}, {0.8, -1.5}, {1.6, -0.4}};
  for (int v = 0; v < 3; ++v) input.views[v].rpc = input.views[v].rpc.WithBias(b[v]);
  BiasOptions options;
  const BiasEstimate on = EstimateViewBiases(input, kAllPairs, options);
  options.refine.register_to_initial = 0;
  const BiasEstimate off = EstimateViewBiases(input, kAllPairs, options);
  EXPECT_GT(off.datum_shift_m.norm(), 0.03);  // not the reference view's datum
  EXPECT_LT((on.datum_shift_m - off.datum_shift_m).norm(), 1e-9)
      << on.datum_shift_m.transpose() << " vs " << off.datum_shift_m.transpose();
}

}  // namespace
}  // namespace satmesh
