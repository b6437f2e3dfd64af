#include "core/dsm/dsm.h"

#include <Eigen/Geometry>
#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <unistd.h>
#include <filesystem>
#include <limits>
#include <random>

#include "core/common/error.h"
#include "core/common/gdal_init.h"

namespace satmesh {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
const char* kUtm31 = "EPSG:32631";

std::string Wkt(const char* crs) {
  OGRSpatialReference srs;
  srs.SetFromUserInput(crs);
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  std::string out = wkt;
  CPLFree(wkt);
  return out;
}

// A w x h north-up grid of 0.5 m cells at UTM-like coordinates, z = f(i, j).
template <typename F>
Dsm CreateDsm(int w, int h, F f, double cell = 0.5) {
  Dsm dsm;
  dsm.width = w;
  dsm.height = h;
  dsm.geo_transform = {698000.25, cell, 0, 4793000.75, 0, -cell};
  dsm.crs_wkt = Wkt(kUtm31);
  dsm.z.resize(size_t(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) dsm.at(i, j) = f(i, j);
  return dsm;
}

Eigen::Vector3f Normal(const TriangleMesh& m, const Eigen::Vector3i& f) {
  return (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]);
}

std::string TempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("satmesh_dsm_test_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

TEST(MeshFromDsm, FullGridTwoTrianglesPerBlockNormalsUp) {
  Dsm dsm = CreateDsm(4, 3, [](int i, int j) { return 100.f + i - 0.5f * j; });
  TriangleMesh mesh = MeshFromDsm(dsm);
  EXPECT_EQ(mesh.num_vertices(), 12u);
  EXPECT_EQ(mesh.num_faces(), 2u * 3 * 2);
  EXPECT_EQ(mesh.crs, dsm.crs_wkt);
  EXPECT_DOUBLE_EQ(mesh.origin.x(), std::round(698000.25 + 2 * 0.5));
  EXPECT_DOUBLE_EQ(mesh.origin.y(), std::round(4793000.75 - 1.5 * 0.5));
  for (const auto& f : mesh.faces) EXPECT_GT(Normal(mesh, f).z(), 0.f);
  // Vertex 0 is cell (0, 0).
  Eigen::Vector3d p = mesh.AbsoluteVertex(mesh.faces[0][0]);
  EXPECT_NEAR(p.z(), dsm.at(0, 0), 1e-4);
}

TEST(MeshFromDsm, SouthUpGridNormalsStillUp) {
  Dsm dsm = CreateDsm(3, 3, [](int i, int j) { return float(i * j); });
  dsm.geo_transform[5] = 0.5;
  TriangleMesh mesh = MeshFromDsm(dsm);
  ASSERT_EQ(mesh.num_faces(), 8u);
  for (const auto& f : mesh.faces) EXPECT_GT(Normal(mesh, f).z(), 0.f);
}

TEST(MeshFromDsm, DiagonalWithSmallerHeightDifference) {
  // a b    a-d differ by 0.1, b-c by 4: the diagonal joins a and d.
  // c d
  Dsm dsm = CreateDsm(2, 2, [](int i, int j) {
    const float z[2][2] = {{0.f, 5.f}, {1.f, 0.1f}};
    return z[j][i];
  });
  TriangleMesh mesh = MeshFromDsm(dsm);
  ASSERT_EQ(mesh.num_faces(), 2u);
  auto has = [&](const Eigen::Vector3i& f, float z) {
    for (int k = 0; k < 3; ++k)
      if (std::abs(mesh.AbsoluteVertex(f[k]).z() - z) < 1e-4) return true;
    return false;
  };
  for (const auto& f : mesh.faces) {
    EXPECT_TRUE(has(f, 0.f) && has(f, 0.1f));
    EXPECT_GT(Normal(mesh, f).z(), 0.f);
  }
}

TEST(MeshFromDsm, ThreeValidCellsMakeOneTriangleIsolatedCellsNoVertex) {
  Dsm dsm = CreateDsm(5, 4, [](int, int) { return kNaN; });
  dsm.at(0, 0) = 1.f;  // a, b, c of the first block: one triangle
  dsm.at(1, 0) = 2.f;
  dsm.at(0, 1) = 3.f;
  dsm.at(4, 3) = 9.f;  // isolated
  dsm.at(3, 3) = 9.f;  // a pair: no triangle either
  TriangleMesh mesh = MeshFromDsm(dsm);
  EXPECT_EQ(mesh.num_faces(), 1u);
  EXPECT_EQ(mesh.num_vertices(), 3u);
  EXPECT_GT(Normal(mesh, mesh.faces[0]).z(), 0.f);
}

TEST(MeshFromDsm, AllNoData) {
  TriangleMesh mesh = MeshFromDsm(CreateDsm(3, 3, [](int, int) { return kNaN; }));
  EXPECT_EQ(mesh.num_faces(), 0u);
  EXPECT_EQ(mesh.num_vertices(), 0u);
}

TEST(DsmFromMesh, PlaneOnOffsetFinerGrid) {
  // A plane is reproduced exactly by linear interpolation at any point inside.
  auto plane = [](double x, double y) { return 120.0 + 0.3 * (x - 698000) - 0.2 * (y - 4793000); };
  Dsm coarse = CreateDsm(10, 10, [&](int i, int j) { return 0.f; });
  for (int j = 0; j < 10; ++j)
    for (int i = 0; i < 10; ++i)
      coarse.at(i, j) = float(plane(coarse.CellCenterX(i), coarse.CellCenterY(j)));
  TriangleMesh mesh = MeshFromDsm(coarse);
  Dsm fine = CreateDsm(30, 30, [](int, int) { return 0.f; }, 0.2);
  fine.geo_transform[0] += 0.013;
  fine.geo_transform[3] -= 0.029;
  Dsm out = DsmFromMesh(mesh, fine);
  ASSERT_EQ(out.width, 30);
  int compared = 0;
  for (int j = 0; j < 30; ++j) {
    for (int i = 0; i < 30; ++i) {
      const double x = fine.CellCenterX(i), y = fine.CellCenterY(j);
      const bool inside = x > coarse.CellCenterX(0) && x < coarse.CellCenterX(9) &&
                          y < coarse.CellCenterY(0) && y > coarse.CellCenterY(9);
      if (!inside) continue;
      ASSERT_TRUE(std::isfinite(out.at(i, j))) << i << "," << j;
      EXPECT_NEAR(out.at(i, j), plane(x, y), 1e-4);
      ++compared;
    }
  }
  EXPECT_GT(compared, 300);
  EXPECT_TRUE(std::isnan(out.at(29, 29)));  // outside the mesh
}

TEST(DsmFromMesh, HighestHitWins) {
  // Two horizontal squares, z = 1 (big) and z = 3 (small, over the centre).
  TriangleMesh mesh;
  mesh.origin = {500000, 4000000, 100};
  mesh.vertices = {{0, 0, 1}, {4, 0, 1}, {4, 4, 1}, {0, 4, 1},
                   {1, 1, 3}, {3, 1, 3}, {3, 3, 3}, {1, 3, 3}};
  mesh.faces = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  Dsm grid;
  grid.width = grid.height = 4;
  grid.geo_transform = {500000, 1, 0, 4000004, 0, -1};
  Dsm out = DsmFromMesh(mesh, grid);
  EXPECT_NEAR(out.at(0, 0), 101.f, 1e-4);
  EXPECT_NEAR(out.at(1, 1), 103.f, 1e-4);
  EXPECT_NEAR(out.at(2, 2), 103.f, 1e-4);
  EXPECT_NEAR(out.at(3, 2), 101.f, 1e-4);
}

// True if valid cell (i, j) is a corner of a 2x2 block with >= 3 valid cells, i.e. a
// vertex of some triangle of MeshFromDsm. Other valid cells (isolated, or in 1-cell-wide
// lines/diagonals) cannot make a triangle.
bool InSomeTriangle(const Dsm& dsm, int i, int j) {
  auto valid = [&](int a, int b) {
    return a >= 0 && b >= 0 && a < dsm.width && b < dsm.height && std::isfinite(dsm.at(a, b));
  };
  if (!valid(i, j)) return false;
  for (int bj = j - 1; bj <= j; ++bj)
    for (int bi = i - 1; bi <= i; ++bi)
      if (valid(bi, bj) + valid(bi + 1, bj) + valid(bi, bj + 1) + valid(bi + 1, bj + 1) >= 3)
        return true;
  return false;
}

struct RoundTripStats {
  int valid = 0, compared = 0, untriangulated = 0, lost = 0, holes_filled = 0;
  double max_abs_diff = 0;
};

// dsm -> MeshFromDsm -> DsmFromMesh on the same grid, compared cell by cell.
RoundTripStats RoundTrip(const Dsm& dsm, size_t* num_vertices = nullptr) {
  TriangleMesh mesh = MeshFromDsm(dsm);
  if (num_vertices) *num_vertices = mesh.num_vertices();
  Dsm out = DsmFromMesh(mesh, dsm);
  RoundTripStats s;
  for (int j = 0; j < dsm.height; ++j) {
    for (int i = 0; i < dsm.width; ++i) {
      const float in = dsm.at(i, j), back = out.at(i, j);
      if (std::isnan(in)) {
        s.holes_filled += !std::isnan(back);
        continue;
      }
      ++s.valid;
      if (!InSomeTriangle(dsm, i, j)) {
        ++s.untriangulated;
        continue;
      }
      if (std::isnan(back)) {
        ++s.lost;
        continue;
      }
      ++s.compared;
      s.max_abs_diff = std::max(s.max_abs_diff, std::abs(double(back) - double(in)));
    }
  }
  return s;
}

TEST(DsmRoundTrip, MeshFromDsmThenDsmFromMeshWithHoles) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> height(100.f, 130.f);
  std::bernoulli_distribution hole(0.2);
  Dsm dsm = CreateDsm(60, 50, [&](int, int) { return hole(rng) ? kNaN : height(rng); });
  size_t num_vertices = 0;
  RoundTripStats s = RoundTrip(dsm, &num_vertices);
  EXPECT_EQ(s.holes_filled, 0);                   // holes stay holes
  EXPECT_EQ(s.lost, 0);                           // boundary vertices are hit too
  EXPECT_EQ(size_t(s.compared), num_vertices);    // a vertex per triangulated cell
  EXPECT_GT(s.untriangulated, 0);                 // the fixture does have some
  EXPECT_LT(s.max_abs_diff, 1e-3);
  EXPECT_GT(s.compared, 2000);
}

TEST(DsmRoundTrip, PleiadesMarseilleS2pDsm) {
  const std::string path =
      std::string(SATMESH_SHARED_DATA_DIR) + "/pleiades_marseille_triplet/s2p_dsm.tif";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "missing " << path;
  Dsm dsm = ReadDsm(path);
  RoundTripStats s = RoundTrip(dsm);
  std::printf(
      "s2p_dsm.tif %dx%d: valid %d, compared %d, max |diff| %.3g m, lost (NaN back) %d, "
      "untriangulated valid cells %d, holes filled %d\n",
      dsm.width, dsm.height, s.valid, s.compared, s.max_abs_diff, s.lost, s.untriangulated,
      s.holes_filled);
  EXPECT_EQ(s.lost, 0);
  EXPECT_EQ(s.holes_filled, 0);
  EXPECT_LT(s.max_abs_diff, 1e-3);
  EXPECT_EQ(s.compared + s.untriangulated, s.valid);
  EXPECT_GT(s.compared, s.valid / 2);
}

// A city-like grid: a sloped street, 10 m high blocks of 15 x 12 m on a 30 x 24 m period
// (walls: ~7% of the cells' second differences), white noise of `sigma`, some NaN.
Dsm NoisyCity(double sigma, uint64_t seed) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<float> noise(0, float(sigma));
  return CreateDsm(300, 200, [&](int i, int j) {
    if ((i * 7 + j * 3) % 97 == 0) return kNaN;
    const float base = 0.02f * i + 0.01f * j;
    const bool block = (i / 30) % 2 == 1 && (j / 24) % 2 == 0;
    return base + (block ? 10.0f : 0.0f) + noise(gen);
  });
}

TEST(DsmCellNoise, RecoversWhiteNoiseBesideWallsAndSlopes) {
  for (double sigma : {0.02, 0.05, 0.15, 0.3}) {
    const double estimate = DsmCellNoise(NoisyCity(sigma, 7));
    // The walls' differences lie far outside the noise's: they widen the MAD by about their
    // share of the differences, and no more however high the walls.
    EXPECT_NEAR(estimate, 1.05 * sigma, 0.05 * sigma) << "sigma " << sigma;
  }
  // A noiseless sloped city: its smooth parts have zero second differences.
  EXPECT_LT(DsmCellNoise(NoisyCity(0, 7)), 1e-4);
}

TEST(DsmCellNoise, SmoothedNoiseReadsLower) {
  // The same noise averaged over 2 x 2 cells halves its sigma and correlates neighbours,
  // which lowers the second differences further: the estimate measures what a mesh
  // through the cells would hold at one cell's scale.
  const Dsm dsm = NoisyCity(0.2, 3);
  Dsm smoothed = dsm;
  for (int j = 0; j + 1 < dsm.height; ++j)
    for (int i = 0; i + 1 < dsm.width; ++i)
      smoothed.at(i, j) = 0.25f * (dsm.at(i, j) + dsm.at(i + 1, j) + dsm.at(i, j + 1) +
                                   dsm.at(i + 1, j + 1));
  EXPECT_LT(DsmCellNoise(smoothed), 0.5 * DsmCellNoise(dsm));
}

TEST(DsmCellNoise, TooFewCellsIsNaN) {
  EXPECT_TRUE(std::isnan(DsmCellNoise(CreateDsm(5, 5, [](int, int) { return 1.0f; }))));
  EXPECT_TRUE(std::isnan(DsmCellNoise(CreateDsm(40, 40, [](int, int) { return kNaN; }))));
}

TEST(DsmCellNoise, PleiadesMarseilleS2pDsmIsSharp) {
  const std::string path =
      std::string(SATMESH_SHARED_DATA_DIR) + "/pleiades_marseille_triplet/s2p_dsm.tif";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "missing " << path;
  const double noise = DsmCellNoise(ReadDsm(path));
  std::printf("s2p_dsm.tif: cell noise %.4f m\n", noise);
  // The triplet's s2p DSM holds its 0.5 m cells to ~0.05 m (python/numpy: 0.051 m).
  EXPECT_NEAR(noise, 0.051, 0.005);
}

TEST(DsmIo, WriteReadRoundTrip) {
  EnsureGdalInitialized();
  Dsm dsm = CreateDsm(7, 5, [](int i, int j) { return (i + j) % 3 ? 50.f + i : kNaN; });
  const std::string path = TempPath("rt.tif");
  WriteDsm(path, dsm);
  Dsm back = ReadDsm(path);
  std::filesystem::remove(path);
  EXPECT_EQ(back.width, 7);
  EXPECT_EQ(back.height, 5);
  for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(back.geo_transform[k], dsm.geo_transform[k]);
  OGRSpatialReference a, b;
  a.importFromWkt(dsm.crs_wkt.c_str());
  b.importFromWkt(back.crs_wkt.c_str());
  EXPECT_TRUE(a.IsSame(&b));
  for (size_t k = 0; k < dsm.z.size(); ++k) {
    if (std::isnan(dsm.z[k])) EXPECT_TRUE(std::isnan(back.z[k]));
    else EXPECT_EQ(back.z[k], dsm.z[k]);
  }
}

// Writes a 3x2 GeoTIFF with the given geotransform and nodata -9999 through GDAL.
void WriteRawTiff(const std::string& path, const double* gt) {
  GDALDriver* drv = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = drv->Create(path.c_str(), 3, 2, 1, GDT_Float32, nullptr);
  ds->SetGeoTransform(const_cast<double*>(gt));
  float z[6] = {1, -9999, 3, 4, 5, -9999};
  ds->GetRasterBand(1)->SetNoDataValue(-9999);
  EXPECT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 3, 2, z, 3, 2, GDT_Float32, 0, 0,
                                           nullptr),
            CE_None);
  GDALClose(ds);
}

TEST(DsmIo, NoDataBecomesNaN) {
  EnsureGdalInitialized();
  const std::string path = TempPath("nodata.tif");
  const double gt[6] = {10, 1, 0, 20, 0, -1};
  WriteRawTiff(path, gt);
  Dsm dsm = ReadDsm(path);
  std::filesystem::remove(path);
  ASSERT_EQ(dsm.z.size(), 6u);
  EXPECT_EQ(dsm.z[0], 1.f);
  EXPECT_TRUE(std::isnan(dsm.z[1]));
  EXPECT_TRUE(std::isnan(dsm.z[5]));
  EXPECT_EQ(dsm.z[4], 5.f);
}

TEST(DsmIo, RotatedGridRejectedNamingFile) {
  EnsureGdalInitialized();
  const std::string path = TempPath("rotated.tif");
  const double gt[6] = {10, 1, 0.1, 20, 0.1, -1};
  WriteRawTiff(path, gt);
  try {
    ReadDsm(path);
    ADD_FAILURE() << "rotated grid accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidInput);
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(DsmIo, MissingFileIsNotFound) {
  try {
    ReadDsm("/nonexistent/dsm.tif");
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dsm.tif"), std::string::npos);
  }
}

}  // namespace
}  // namespace satmesh
