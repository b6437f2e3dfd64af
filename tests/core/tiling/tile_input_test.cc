#include "core/tiling/tile_input.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/geo/crs.h"

namespace satmesh {
namespace {

// A 100 x 80 DSM of 0.5 m cells in UTM 31N with relief in both directions.
Dsm TestDsm() {
  Dsm dsm;
  dsm.width = 100, dsm.height = 80;
  dsm.geo_transform = {698000, 0.5, 0, 4792900, 0, -0.5};
  dsm.crs_wkt = CrsToWkt("EPSG:32631");
  dsm.z.resize(size_t(dsm.width) * dsm.height);
  for (int j = 0; j < dsm.height; ++j)
    for (int i = 0; i < dsm.width; ++i) dsm.at(i, j) = float(80 + 0.1 * i + 3 * std::sin(0.3 * j));
  return dsm;
}

// A level that restarts from the initial surface gets the DSM meshed at half the level's
// triangle edge, in the frame of the coarse initial mesh.
TEST(TileInput, InitialSurfaceForAnEdgeIsTheDsmAtHalfThatEdge) {
  const Dsm dsm = TestDsm();
  JobSpec spec;  // no image: only the surface is prepared
  spec.initial_dsm = "test.tif";
  const TileInput coarse = PrepareTileInput(spec, dsm, /*coarse_cell_m=*/2.0);
  const TileInput fine = PrepareTileInput(spec, dsm, /*coarse_cell_m=*/0.5);
  ASSERT_TRUE(coarse.refine.initial_for_edge);
  EXPECT_EQ(coarse.refine.initial_mesh.vertices.size(), 25u * 20u);
  EXPECT_EQ(fine.refine.initial_mesh.vertices.size(), 100u * 80u);

  const TriangleMesh at_1m = coarse.refine.initial_for_edge(1.0);  // 0.5 m cells: all of it
  ASSERT_EQ(at_1m.vertices.size(), fine.refine.initial_mesh.vertices.size());
  EXPECT_EQ(at_1m.faces.size(), fine.refine.initial_mesh.faces.size());
  double max_diff = 0;
  for (size_t i = 0; i < at_1m.vertices.size(); ++i)
    max_diff = std::max(max_diff,
                        double((at_1m.vertices[i] - fine.refine.initial_mesh.vertices[i]).norm()));
  EXPECT_LT(max_diff, 1e-4);
  EXPECT_EQ(coarse.refine.initial_for_edge(4.0).vertices.size(), 25u * 20u);  // 2 m cells
  EXPECT_EQ(coarse.refine.initial_for_edge(3.0).vertices.size(), 34u * 27u);  // 1.5 m cells
  EXPECT_EQ(coarse.refine.initial_for_edge(0.6).vertices.size(), 100u * 80u);  // never finer
}

// The DSM's holes are filled before anything is meshed from it; with fill_holes_m = 0
// they stay open.
// With sharp_dsm_noise_cells > 0 a DSM's cells are meshed as they are where its noise at
// one cell is at most that many cells, else block-averaged to the coarse cell; by default
// always averaged.
TEST(TileInput, ASharpDsmIsMeshedAtItsCellsANoisyOneFromBlockAverages) {
  JobSpec spec;
  spec.initial_dsm = "test.tif";
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, TestDsm(), 2.0), 2.0);  // off by default
  spec.refine.sharp_dsm_noise_cells = 0.2;
  const Dsm smooth = TestDsm();
  Dsm noisy = smooth;
  std::mt19937 gen(5);
  std::normal_distribution<float> noise(0, 0.15f);  // 0.3 cell
  for (float& z : noisy.z) z += noise(gen);
  double noise_m = 0;
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, smooth, 2.0, &noise_m), 0.5);
  EXPECT_LT(noise_m, 0.01);
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, noisy, 2.0, &noise_m), 2.0);
  EXPECT_NEAR(noise_m, 0.15, 0.015);
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, smooth, 0.5), 0.5);  // never coarser
  spec.refine.sharp_dsm_noise_cells = 0.35;                          // the bound, in cells
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, noisy, 2.0), 0.5);
  spec.refine.sharp_dsm_noise_cells = 0;  // off: always averaged
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, smooth, 2.0), 2.0);
  // PrepareTileInput meshes by it.
  spec.refine.sharp_dsm_noise_cells = 0.2;
  EXPECT_EQ(PrepareTileInput(spec, smooth, 2.0).refine.initial_mesh.vertices.size(), 100u * 80u);
  EXPECT_EQ(PrepareTileInput(spec, noisy, 2.0).refine.initial_mesh.vertices.size(), 25u * 20u);
  // A DSM the user trusts (trusted_initial: LiDAR, a city model) is meshed at its cells
  // whatever its noise, never coarser than the coarse cell.
  spec.refine.sharp_dsm_noise_cells = 0;
  spec.refine.trusted_initial = 1;
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, noisy, 2.0), 0.5);
  EXPECT_DOUBLE_EQ(InitialMeshCell(spec.refine, smooth, 0.25), 0.25);
  EXPECT_EQ(PrepareTileInput(spec, noisy, 2.0).refine.initial_mesh.vertices.size(), 100u * 80u);
}

TEST(TileInput, FillsTheDsmHolesBeforeMeshing) {
  Dsm dsm = TestDsm();
  for (int j = 30; j < 34; ++j)
    for (int i = 40; i < 44; ++i) dsm.at(i, j) = std::nanf("");
  JobSpec spec;
  spec.initial_dsm = "test.tif";
  const TileInput filled = PrepareTileInput(spec, dsm, /*coarse_cell_m=*/0.5);
  EXPECT_EQ(filled.filled_dsm_cells, 16u);
  EXPECT_EQ(filled.refine.initial_mesh.vertices.size(), 100u * 80u);
  spec.fill_holes_m = 0;
  const TileInput open = PrepareTileInput(spec, dsm, /*coarse_cell_m=*/0.5);
  EXPECT_EQ(open.filled_dsm_cells, 0u);
  EXPECT_EQ(open.refine.initial_mesh.vertices.size(), 100u * 80u - 16u);
}

}  // namespace
}  // namespace satmesh
