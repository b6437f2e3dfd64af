#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/common/error.h"
#include "core/geo/crs.h"
#include "core/tiling/tile_plan.h"
#include "core/tiling/memory_budget.h"
#include "tests/scratch_dir.h"

namespace satmesh {
namespace {

// A 100 x 80 DSM of 0.5 m cells (50 m x 40 m) in UTM 17N; z = column index.
std::string WriteTestDsm(const std::string& name, const std::string& crs = "EPSG:32617") {
  Dsm dsm;
  dsm.width = 100, dsm.height = 80;
  dsm.geo_transform = {435000, 0.5, 0, 3356040, 0, -0.5};
  dsm.crs_wkt = CrsToWkt(crs);
  dsm.z.resize(size_t(dsm.width) * dsm.height);
  for (int j = 0; j < dsm.height; ++j)
    for (int i = 0; i < dsm.width; ++i) dsm.at(i, j) = float(i);
  // Per process: another checkout's test run on the machine may write the same name.
  const auto path = std::filesystem::temp_directory_path() /
                    ("tiling_plan_" + name + "_" + std::to_string(::getpid()) + ".tif");
  WriteDsm(path.string(), dsm);
  testing::RemoveAtExit(path);
  return path.string();
}

JobSpec Spec(const std::string& dsm_path) {
  JobSpec spec;
  spec.images = {{"a.tif"}, {"b.tif"}};  // PlanJob reads only the DSM
  spec.initial_dsm = dsm_path;
  return spec;
}

TEST(TilingOptions, DefaultsAreValidAndBadValuesNamed) {
  EXPECT_EQ(TilingOptions{}.Check(), "");
  TilingOptions o;
  o.workers = 0;
  EXPECT_NE(o.Check().find("tiling.workers"), std::string::npos);
  o = {};
  o.overlap_m = -1;
  EXPECT_NE(o.Check().find("tiling.overlap_m"), std::string::npos);
  o = {};
  o.memory_budget_mb = -5;
  EXPECT_NE(o.Check().find("tiling.memory_budget_mb"), std::string::npos);
}

TEST(MemoryBudget, DefaultIsAQuarterOfTheMachineSharedByTheWorkers) {
  const double one = DefaultMemoryBudgetMb(1);
  EXPECT_GT(one, 100);  // any machine that runs the tests has 400 MB
  EXPECT_DOUBLE_EQ(DefaultMemoryBudgetMb(4), one / 4);
  TilingOptions o;
  EXPECT_DOUBLE_EQ(MemoryBudgetMb(o), one);
  o.memory_budget_mb = 1234;
  EXPECT_DOUBLE_EQ(MemoryBudgetMb(o), 1234);
}

TEST(PlanJob, EstimatesEachTilesMemoryFromItsCells) {
  // No readable image: the estimate is the fixed part and the DSM cells' meshes.
  JobSpec spec = Spec(WriteTestDsm("estimate"));
  spec.tiling.tile_size_m = 20;
  const JobPlan plan = PlanJob(spec);
  ASSERT_EQ(plan.tiles.size(), 6u);
  for (const PlannedTile& t : plan.tiles) {
    EXPECT_EQ(t.memory.views, 0);
    EXPECT_DOUBLE_EQ(t.memory.dsm_cells, double(t.padded_cells.width) * t.padded_cells.height);
    EXPECT_NEAR(t.memory.peak_mb, kBaseMb + kBytesPerDsmCell * t.memory.dsm_cells / (1 << 20), 1e-9);
  }
}

TEST(PlanJob, DefaultIsOneTileOverTheDsm) {
  const JobPlan plan = PlanJob(Spec(WriteTestDsm("one")));
  ASSERT_EQ(plan.tiles.size(), 1u);
  const PlannedTile& t = plan.tiles[0];
  EXPECT_EQ(t.core_cells.width, 100);
  EXPECT_EQ(t.core_cells.height, 80);
  EXPECT_EQ(t.padded_cells.width, 100);  // overlap clipped to the DSM
  EXPECT_DOUBLE_EQ(t.core.xmin, 435000);
  EXPECT_DOUBLE_EQ(t.core.ymax, 3356040);
  EXPECT_DOUBLE_EQ(t.core.ymin, 3356000);
}

TEST(PlanJob, CoresPartitionTheAoiAndPaddingAddsTheOverlap) {
  JobSpec spec = Spec(WriteTestDsm("grid"));
  spec.tiling.tile_size_m = 20;  // 40 cells
  spec.tiling.overlap_m = 3;     // 6 cells
  const JobPlan plan = PlanJob(spec);
  EXPECT_EQ(plan.nx, 3);
  EXPECT_EQ(plan.ny, 2);
  ASSERT_EQ(plan.tiles.size(), 6u);
  std::vector<int> covered(100 * 80, 0);
  for (const auto& t : plan.tiles) {
    for (int r = t.core_cells.row0; r < t.core_cells.row0 + t.core_cells.height; ++r)
      for (int c = t.core_cells.col0; c < t.core_cells.col0 + t.core_cells.width; ++c) covered[r * 100 + c]++;
    EXPECT_EQ(t.padded_cells.col0, std::max(0, t.core_cells.col0 - 6));
    EXPECT_EQ(t.padded_cells.col0 + t.padded_cells.width,
              std::min(100, t.core_cells.col0 + t.core_cells.width + 6));
  }
  for (int c : covered) ASSERT_EQ(c, 1);
  // (0, 0) is the south-west tile; y grows northwards; the last column is 20 cells wide.
  const PlannedTile& sw = plan.tiles[plan.IndexOf(0, 0)];
  EXPECT_EQ(sw.core_cells.row0 + sw.core_cells.height, 80);
  EXPECT_DOUBLE_EQ(sw.core.ymin, 3356000);
  EXPECT_EQ(plan.tiles[plan.IndexOf(2, 1)].core_cells.width, 20);
  EXPECT_EQ(plan.tiles[plan.IndexOf(2, 1)].core_cells.row0, 0);
  EXPECT_EQ(sw.Name(), "0_0");
}

TEST(PlanJob, ASliverUnderHalfATileJoinsItsNeighbour) {
  JobSpec spec = Spec(WriteTestDsm("sliver"));
  spec.tiling.tile_size_m = 16.5;  // 33 cells: 100 = 33 + 33 + 34, 80 = 33 + 47
  const JobPlan plan = PlanJob(spec);
  EXPECT_EQ(plan.nx, 3);
  EXPECT_EQ(plan.ny, 2);
  EXPECT_EQ(plan.tiles[plan.IndexOf(2, 0)].core_cells.width, 34);
  EXPECT_EQ(plan.tiles[plan.IndexOf(0, 1)].core_cells.height, 47);
  EXPECT_EQ(plan.tiles[plan.IndexOf(0, 1)].core_cells.row0, 0);
}

TEST(PlanJob, AutomaticTilesAreBalancedAndFitTheBudget) {
  // No readable image: a tile's estimate is the fixed part and its padded DSM cells.
  JobSpec spec = Spec(WriteTestDsm("balanced"));
  spec.tiling.overlap_m = 1;  // 2 cells
  spec.tiling.memory_budget_mb = kBaseMb + kBytesPerDsmCell * 2000.0 / (1 << 20);
  const JobPlan plan = PlanJob(spec);
  EXPECT_TRUE(plan.auto_tiled);
  ASSERT_GT(plan.tiles.size(), 1u);
  int min_w = 1 << 30, max_w = 0, min_h = 1 << 30, max_h = 0;
  long cells = 0;
  for (const PlannedTile& t : plan.tiles) {
    EXPECT_LE(t.memory.peak_mb, spec.tiling.memory_budget_mb) << t.Name();
    min_w = std::min(min_w, t.core_cells.width), max_w = std::max(max_w, t.core_cells.width);
    min_h = std::min(min_h, t.core_cells.height), max_h = std::max(max_h, t.core_cells.height);
    cells += long(t.core_cells.width) * t.core_cells.height;
  }
  // Equal to a cell (the last column does not take a remainder), covering the AOI.
  EXPECT_LE(max_w - min_w, 1);
  EXPECT_LE(max_h - min_h, 1);
  EXPECT_EQ(cells, 100L * 80);
  EXPECT_EQ(plan.tile_cells, std::max(max_w, max_h));
}

TEST(PlanJob, PolygonAoiKeepsTheTilesItMeets) {
  JobSpec spec = Spec(WriteTestDsm("poly"));
  spec.tiling.tile_size_m = 20;
  // A thin triangle in the south-west corner: only tile 0_0 (x < 20 m, y < 20 m).
  spec.aoi.polygon = {{435001, 3356001}, {435015, 3356001}, {435001, 3356015}};
  const JobPlan plan = PlanJob(spec);
  ASSERT_EQ(plan.tiles.size(), 1u);
  EXPECT_EQ(plan.tiles[0].Name(), "0_0");
  EXPECT_EQ(plan.aoi_cells.width, 28);  // centres in [435001, 435015]: 2 .. 29
  EXPECT_EQ(plan.aoi_cells.col0, 2);
}

TEST(PlanJob, AoiInAnotherCrsIsMappedToTheGrid) {
  JobSpec spec = Spec(WriteTestDsm("geo"));
  // The UTM box [435010, 435030] x [3356010, 3356030] given in lon/lat.
  const CrsTransform to_geo("EPSG:32617", "EPSG:4326");
  const Eigen::Vector3d a = to_geo.Apply({435010, 3356010, 0}), b = to_geo.Apply({435030, 3356030, 0});
  spec.aoi.crs = "EPSG:4326";
  spec.aoi.polygon = {{a.x(), a.y()}, {b.x(), a.y()}, {b.x(), b.y()}, {a.x(), b.y()}};
  const JobPlan plan = PlanJob(spec);
  // Lines of constant longitude are not grid columns: allow a cell of skew.
  EXPECT_NEAR(plan.aoi_cells.col0, 20, 1);
  EXPECT_NEAR(plan.aoi_cells.width, 40, 2);
  EXPECT_NEAR(plan.aoi_cells.row0, 20, 1);
  EXPECT_NEAR(plan.aoi_cells.height, 40, 2);
}

TEST(PlanJob, AoiOutsideTheDsmOrGeographicDsmThrows) {
  JobSpec spec = Spec(WriteTestDsm("outside"));
  spec.aoi.polygon = {{0, 0}, {10, 0}, {10, 10}};
  EXPECT_THROW(PlanJob(spec), Error);
  EXPECT_THROW(PlanJob(Spec(WriteTestDsm("wgs84", "EPSG:4326"))), Error);
}

TEST(ReadDsmWindow, CellsOutsideTheRasterAreNan) {
  const Dsm window = ReadDsmWindow(WriteTestDsm("window"), PixelWindow{95, -2, 10, 4});
  EXPECT_EQ(window.width, 10);
  EXPECT_DOUBLE_EQ(window.geo_transform[0], 435000 + 95 * 0.5);
  EXPECT_DOUBLE_EQ(window.geo_transform[3], 3356040 + 1.0);
  EXPECT_TRUE(std::isnan(window.at(0, 0)));   // row -2
  EXPECT_EQ(window.at(0, 2), 95.f);
  EXPECT_EQ(window.at(4, 3), 99.f);
  EXPECT_TRUE(std::isnan(window.at(5, 3)));   // column 100
}

}  // namespace
}  // namespace satmesh
