// Comparing surfaces over one support (surface_comparison.h), the measure of the held-out
// checks on real imagery (tests/e2e/pleiades_heldout_test.sh).
#include "core/refine/surface_comparison.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

using testing::DefaultViews;
using testing::MakePlaneInput;
using testing::Plane;
using testing::PlaneMesh;

const std::vector<std::pair<int, int>> kPairs = {{0, 1}, {0, 2}, {1, 2}};

// The faces of `mesh` whose vertices all lie at x < 0 (the vertices kept as they are).
TriangleMesh WestHalf(const TriangleMesh& mesh) {
  TriangleMesh half = mesh;
  half.faces.clear();
  for (const auto& f : mesh.faces)
    if (mesh.vertices[f[0]].x() < 0 && mesh.vertices[f[1]].x() < 0 && mesh.vertices[f[2]].x() < 0)
      half.faces.push_back(f);
  return half;
}

// One surface alone: its windows are its own, and its means (common and own) are
// MeasureMeanZncc's.
TEST(CommonWindowZncc, OneSurfaceGivesItsOwnMean) {
  const Plane plane;
  const TriangleMesh exact = PlaneMesh(plane, 40, 1.0, 0.0);
  const RefineInput input = MakePlaneInput(plane, DefaultViews(), exact);
  const auto common = CommonWindowZncc(input, {exact}, kPairs, 0);
  ASSERT_EQ(common.size(), 1u);
  ASSERT_EQ(common[0].size(), kPairs.size());
  for (size_t k = 0; k < kPairs.size(); ++k) {
    EXPECT_NEAR(common[0][k].mean_zncc, MeasureMeanZncc(input, exact, {kPairs[k]}, 0), 1e-4);
    EXPECT_EQ(common[0][k].own_mean_zncc, common[0][k].mean_zncc);
    EXPECT_EQ(common[0][k].own_windows, common[0][k].windows);
    EXPECT_GT(common[0][k].windows, 2 * 100 * 100);  // two directions over the 80 m plane
  }
}

// A surface over half of another's area: the support is where both are (every window
// the half counts, the whole counts too), there they are the same plane and agree, and
// the whole plane's own mean over all its windows is not what is compared.
TEST(CommonWindowZncc, SurfacesAreComparedWhereBothAre) {
  const Plane plane;
  const TriangleMesh exact = PlaneMesh(plane, 40, 1.0, 0.0);
  const TriangleMesh half = WestHalf(exact);
  const RefineInput input = MakePlaneInput(plane, DefaultViews(), exact);
  const auto whole = CommonWindowZncc(input, {exact}, kPairs, 0);
  const auto both = CommonWindowZncc(input, {exact, half}, kPairs, 0);
  const auto alone = CommonWindowZncc(input, {half}, kPairs, 0);
  for (size_t k = 0; k < kPairs.size(); ++k) {
    std::printf("pair %d-%d: whole %ld windows, half %ld, common %ld; common means %.4f / %.4f\n",
                kPairs[k].first, kPairs[k].second, whole[0][k].windows, alone[0][k].windows,
                both[0][k].windows, both[0][k].mean_zncc, both[1][k].mean_zncc);
    EXPECT_EQ(both[0][k].windows, both[1][k].windows);
    EXPECT_EQ(both[0][k].windows, alone[0][k].windows);
    EXPECT_GT(both[0][k].windows, whole[0][k].windows * 4 / 10);
    EXPECT_LT(both[0][k].windows, whole[0][k].windows * 6 / 10);
    EXPECT_NEAR(both[0][k].mean_zncc, both[1][k].mean_zncc, 0.01);
    // each surface's own windows and mean, as measured alone
    EXPECT_EQ(both[0][k].own_windows, whole[0][k].windows);
    EXPECT_EQ(both[1][k].own_windows, alone[0][k].windows);
    EXPECT_NEAR(both[0][k].own_mean_zncc, whole[0][k].mean_zncc, 1e-9);
    EXPECT_NEAR(both[1][k].own_mean_zncc, alone[0][k].mean_zncc, 1e-9);
  }
}

// Over one support the exact plane explains the images better than the plane 1 m above.
TEST(CommonWindowZncc, RanksTheExactSurfaceFirst) {
  const Plane plane;
  const TriangleMesh exact = PlaneMesh(plane, 40, 1.0, 0.0);
  const TriangleMesh above = PlaneMesh(plane, 40, 1.0, 1.0);
  const RefineInput input = MakePlaneInput(plane, DefaultViews(), exact);
  const auto common = CommonWindowZncc(input, {above, exact}, kPairs, 0);
  for (size_t k = 0; k < kPairs.size(); ++k) {
    std::printf("pair %d-%d: 1 m above %.4f, exact %.4f (%ld windows)\n", kPairs[k].first,
                kPairs[k].second, common[0][k].mean_zncc, common[1][k].mean_zncc,
                common[0][k].windows);
    EXPECT_GT(common[1][k].mean_zncc, common[0][k].mean_zncc + 0.02);
  }
}

}  // namespace
}  // namespace satmesh
