#include "core/dsm/fill_holes.h"

#include <gtest/gtest.h>

#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>

namespace satmesh {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// A w x h grid of 0.5 m cells on the tilted plane z = 10 + 0.2 x - 0.1 y (metres).
Dsm TiltedPlane(int w, int h) {
  Dsm dsm;
  dsm.width = w;
  dsm.height = h;
  dsm.geo_transform = {698000.0, 0.5, 0, 4793000.0, 0, -0.5};
  dsm.z.resize(size_t(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) dsm.at(i, j) = float(10 + 0.2 * 0.5 * i - 0.1 * 0.5 * j);
  return dsm;
}

size_t CountNaN(const Dsm& dsm) {
  size_t n = 0;
  for (float z : dsm.z) n += !std::isfinite(z);
  return n;
}

TEST(FillDsmHoles, FillsAHoleFromItsSurroundings) {
  Dsm dsm = TiltedPlane(80, 60);
  const Dsm truth = dsm;
  for (int j = 20; j < 32; ++j)
    for (int i = 30; i < 40; ++i) dsm.at(i, j) = kNaN;  // 12 x 10 cells, 6 x 5 m
  dsm.at(5, 50) = kNaN;                                  // one isolated empty cell
  EXPECT_EQ(FillDsmHoles(&dsm, 50.0), 121u);
  EXPECT_EQ(CountNaN(dsm), 0u);
  // Inverse-distance weighting of a plane: the mean of its rim, so near the plane.
  double worst = 0;
  for (size_t k = 0; k < dsm.z.size(); ++k) worst = std::max(worst, double(std::abs(dsm.z[k] - truth.z[k])));
  EXPECT_LT(worst, 0.3);  // the plane rises 0.6 m across the hole
  EXPECT_NEAR(dsm.at(5, 50), truth.at(5, 50), 0.05);
}

// Issue 17: GDALFillNodata wrote its work rasters into the current directory, so a run
// from an unwritable one (the image's non-root user, a service, `cd /`) failed. /proc
// is unwritable even for root; the fill must neither need nor touch the directory.
TEST(FillDsmHoles, WorksFromAnUnwritableCurrentDirectory) {
  struct RestoreCwd {
    std::filesystem::path path = std::filesystem::current_path();
    ~RestoreCwd() { std::filesystem::current_path(path); }
  } restore;
  ASSERT_EQ(chdir("/proc"), 0);
  const int probe = open("satmesh-probe", O_CREAT | O_WRONLY, 0600);  // access() lets root pass
  ASSERT_LT(probe, 0) << "a file can be created in /proc here: the test proves nothing";
  Dsm dsm = TiltedPlane(40, 30);
  for (int j = 10; j < 16; ++j)
    for (int i = 15; i < 20; ++i) dsm.at(i, j) = kNaN;
  size_t filled = 0;
  EXPECT_NO_THROW(filled = FillDsmHoles(&dsm, 50.0));
  EXPECT_EQ(filled, 30u);
  EXPECT_EQ(CountNaN(dsm), 0u);
}

TEST(FillDsmHoles, LeavesTheOutsideOfTheFootprintAndFarCellsEmpty) {
  Dsm dsm = TiltedPlane(100, 100);
  // Valid data only inside the triangle i + j < 100 (a footprint's corner); the rest is
  // outside the convex hull of the data and must stay empty.
  for (int j = 0; j < 100; ++j)
    for (int i = 0; i < 100; ++i)
      if (i + j >= 100) dsm.at(i, j) = kNaN;
  // A 30 x 30 hole inside the footprint, more than 5 m (10 cells) from data at its centre.
  for (int j = 10; j < 40; ++j)
    for (int i = 10; i < 40; ++i) dsm.at(i, j) = kNaN;
  Dsm far = dsm;
  const size_t outside = CountNaN(dsm) - 900;

  EXPECT_EQ(FillDsmHoles(&dsm, 50.0), 900u);  // 25 m: the whole hole
  EXPECT_EQ(CountNaN(dsm), outside);
  for (int j = 0; j < 100; ++j)
    for (int i = 0; i < 100; ++i)
      if (i + j >= 101) EXPECT_TRUE(std::isnan(dsm.at(i, j))) << i << "," << j;

  const size_t filled = FillDsmHoles(&far, 5.0);  // 10 cells: the rim, not the centre
  EXPECT_GT(filled, 500u);
  EXPECT_LT(filled, 900u);
  EXPECT_TRUE(std::isnan(far.at(25, 25)));
  EXPECT_TRUE(std::isfinite(far.at(10, 25)));
}

TEST(FillDsmHoles, ZeroDistanceOrNoHoleChangesNothing) {
  Dsm dsm = TiltedPlane(20, 20);
  dsm.at(10, 10) = kNaN;
  EXPECT_EQ(FillDsmHoles(&dsm, 0.0), 0u);
  EXPECT_TRUE(std::isnan(dsm.at(10, 10)));
  Dsm full = TiltedPlane(20, 20);
  const Dsm before = full;
  EXPECT_EQ(FillDsmHoles(&full, 50.0), 0u);
  EXPECT_EQ(full.z, before.z);
}

}  // namespace
}  // namespace satmesh
