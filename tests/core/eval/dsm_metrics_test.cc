#include "core/eval/dsm_metrics.h"

#include <gtest/gtest.h>

#include "core/common/error.h"

#include <cmath>
#include <limits>

namespace satmesh {
namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN();

// A 40x40 grid at 0.5 m with a wavy terrain and two blocks (not symmetric under shifts).
Dsm MakeTruth() {
  Dsm d;
  d.width = d.height = 40;
  d.geo_transform = {500000.0, 0.5, 0, 4000000.0, 0, -0.5};
  d.z.resize(40 * 40);
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      float z = 100.f + 1.5f * std::sin(0.31f * i) + 1.0f * std::cos(0.23f * j + 0.4f * i);
      if (i >= 8 && i < 18 && j >= 10 && j < 22) z += 9.f;
      if (i >= 24 && i < 33 && j >= 5 && j < 12) z += 5.f + 0.3f * (i - 24);
      d.at(i, j) = z;
    }
  return d;
}

TEST(ComputeDsmMetrics, KnownResiduals) {
  const std::vector<float> r{0.1f, -0.2f, 0.3f, -0.4f, 0.5f, 2.0f, -5.0f, kNaN};
  const DsmMetrics m = ComputeDsmMetrics(r);
  EXPECT_EQ(m.num_cells, 8u);
  EXPECT_EQ(m.num_valid, 7u);
  EXPECT_DOUBLE_EQ(m.completeness, 6.0 / 8.0);
  EXPECT_DOUBLE_EQ(m.completeness_1m, 5.0 / 8.0);
  EXPECT_DOUBLE_EQ(m.completeness_05m, 4.0 / 8.0);
  EXPECT_NEAR(m.rmse_m, std::sqrt(4.55 / 6.0), 1e-6);
  EXPECT_NEAR(m.median_m, 0.1, 1e-6);
  EXPECT_NEAR(m.nmad_m, 1.4826 * 0.4, 1e-6);  // |r - 0.1| sorted: 0 .2 .3 .4 .5 1.9 5.1
  EXPECT_NEAR(m.perc68_m, 0.5 + 0.08 * 1.5, 1e-6);  // position 0.68 * 6 = 4.08
  EXPECT_NEAR(m.mae_m, 8.5 / 7.0, 1e-6);
}

TEST(ComputeDsmMetrics, EmptyAndAllMissing) {
  EXPECT_EQ(ComputeDsmMetrics({}).num_cells, 0u);
  const DsmMetrics m = ComputeDsmMetrics({kNaN, kNaN});
  EXPECT_EQ(m.num_cells, 2u);
  EXPECT_EQ(m.num_valid, 0u);
  EXPECT_EQ(m.completeness, 0.0);
}

TEST(DsmEvalOptions, DefaultsAreValidAndBadValuesNamed) {
  EXPECT_EQ(DsmEvalOptions{}.Check(), "");
  DsmEvalOptions o;
  o.align.max_shift_m = -1;
  EXPECT_NE(o.Check().find("max_shift_m"), std::string::npos);
  DsmMetricsOptions m;
  m.completeness_threshold_m = 0;
  EXPECT_THROW(ComputeDsmMetrics({1.f}, m), Error);
}

TEST(AlignDsm, RecoversKnownShiftAndOffset) {
  const Dsm truth = MakeTruth();
  Dsm result = truth;
  // Result content moved by +3 cells in i, -2 cells in j, and raised by 1.25 m.
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      const int ti = i - 3, tj = j + 2;
      result.at(i, j) = (ti >= 0 && tj < 40) ? truth.at(ti, tj) + 1.25f : kNaN;
    }
  const Alignment a = AlignDsm(result, truth, {});
  EXPECT_EQ(a.shift_i, -3);
  EXPECT_EQ(a.shift_j, 2);
  EXPECT_DOUBLE_EQ(a.dx_m, -1.5);
  EXPECT_DOUBLE_EQ(a.dy_m, -1.0);  // content moved 2 rows up = 1 m north; back south
  EXPECT_NEAR(a.dz_m, -1.25, 1e-5);

  const DsmEvaluation e = EvaluateDsm(result, truth, {});
  EXPECT_GT(e.all_raw.nmad_m, 0.5);
  EXPECT_NEAR(e.all_aligned.nmad_m, 0.0, 1e-5);
  EXPECT_NEAR(e.all_aligned.median_m, 0.0, 1e-5);
  // Cells whose shifted partner is off the grid are holes: (40-3)*(40-2)/1600 complete.
  EXPECT_NEAR(e.all_aligned.completeness, 37.0 * 38.0 / 1600.0, 1e-9);
}

TEST(AlignDsm, CoarseToFineFindsOddShiftNearTheSearchLimit) {
  const Dsm truth = MakeTruth();
  Dsm result = truth;
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      const int ti = i + 7, tj = j - 5;  // content moved by (-7, +5) cells, lowered 0.4 m
      result.at(i, j) = (ti < 40 && tj >= 0) ? truth.at(ti, tj) - 0.4f : kNaN;
    }
  AlignOptions o;
  o.max_shift_m = 4.0;  // 8 cells: coarse step 2
  const Alignment a = AlignDsm(result, truth, {}, o);
  EXPECT_EQ(a.shift_i, 7);
  EXPECT_EQ(a.shift_j, -5);
  EXPECT_NEAR(a.dz_m, 0.4, 1e-5);
}

TEST(EvaluateDsm, MaskSelectsCellsAndGridsMustMatch) {
  const Dsm truth = MakeTruth();
  Dsm result = truth;
  std::vector<uint8_t> mask(truth.z.size(), 0);
  for (int j = 10; j < 22; ++j)
    for (int i = 8; i < 18; ++i) {
      mask[size_t(j) * 40 + i] = 1;
      result.at(i, j) += 0.7f;  // only the masked block is wrong
    }
  const DsmEvaluation e = EvaluateDsm(result, truth, mask);
  EXPECT_EQ(e.mask_raw.num_cells, 120u);
  EXPECT_NEAR(e.mask_raw.mae_m, 0.7, 1e-5);
  EXPECT_DOUBLE_EQ(e.mask_raw.completeness_1m, 1.0);
  EXPECT_DOUBLE_EQ(e.mask_raw.completeness_05m, 0.0);
  EXPECT_NEAR(e.all_raw.mae_m, 0.7 * 120 / 1600, 1e-5);
  Dsm other = truth;
  other.width = 20;
  EXPECT_THROW(EvaluateDsm(other, truth, mask), Error);
}

}  // namespace
}  // namespace satmesh
