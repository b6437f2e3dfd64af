#include "core/eval/scene_eval.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/dsm/dsm.h"
#include "core/eval/scene_views.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_io.h"
#include "core/synth/scene_writer.h"
#include "tests/tiny_scene.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

// A tiny scene directory by the layout contract: 30x30 cells at 0.5 m, ground at 100 m
// and a 10x10-cell block 8 m high; the initial DSM has its roof 0.8 m too high and holes.
fs::path WriteTinyScene(const std::string& name) {
  EnsureGdalInitialized();
  const fs::path dir = fs::temp_directory_path() / name;
  fs::remove_all(dir);
  fs::create_directories(dir / "truth");
  fs::create_directories(dir / "initial");
  Dsm truth;
  truth.width = truth.height = 30;
  truth.geo_transform = {500000.0, 0.5, 0, 4000015.0, 0, -0.5};
  truth.z.assign(900, 100.f);
  Dsm mask = truth, initial = truth;
  mask.z.assign(900, 0.f);
  for (int j = 10; j < 20; ++j)
    for (int i = 10; i < 20; ++i) {
      truth.at(i, j) = initial.at(i, j) = 108.f;
      initial.at(i, j) += 0.8f;
      if (i > 10 && i < 19 && j > 10 && j < 19) mask.at(i, j) = 1.f;  // edge band removed
    }
  for (int i = 0; i < 30; ++i) initial.at(i, 3) = std::numeric_limits<float>::quiet_NaN();
  WriteDsm((dir / "truth" / "dsm.tif").string(), truth);
  WriteDsm((dir / "truth" / "roof_mask.tif").string(), mask);
  WriteDsm((dir / "initial" / "dsm.tif").string(), initial);
  WriteMesh((dir / "truth" / "mesh.ply").string(), MeshFromDsm(truth));
  return dir;
}

TEST(EvaluateScene, TruthAgainstItselfAndInitial) {
  const fs::path dir = WriteTinyScene("satmesh_eval_tiny_scene");
  const SceneEvaluation e = EvaluateScene(dir.string(), (dir / "truth" / "mesh.ply").string());
  EXPECT_EQ(e.grid_width, 30);
  EXPECT_EQ(e.num_mask_cells, 64u);
  // Result = truth: near perfect in 2.5D and 3D.
  EXPECT_GT(e.result.dsm.mask_raw.completeness_05m, 0.99);
  EXPECT_LT(e.result.dsm.all_raw.nmad_m, 1e-3);
  EXPECT_GT(e.result.mesh3d.all.accuracy[0], 0.999);
  EXPECT_GT(e.result.mesh3d.all.completeness[0], 0.999);
  // Initial: roofs 0.8 m high (out at 0.5 m, in at 1 m), one row of holes.
  EXPECT_DOUBLE_EQ(e.initial.dsm.mask_raw.completeness_05m, 0.0);
  EXPECT_DOUBLE_EQ(e.initial.dsm.mask_raw.completeness_1m, 1.0);
  EXPECT_NEAR(e.initial.dsm.mask_raw.mae_m, 0.8, 1e-5);
  EXPECT_NEAR(e.initial.dsm.all_raw.completeness, 870.0 / 900.0, 1e-9);
  EXPECT_LT(e.initial.mesh3d.all.accuracy[1], e.result.mesh3d.all.accuracy[1]);
  fs::remove_all(dir);
}

TEST(EvaluateScene, MissingFilesAreNamed) {
  const fs::path dir = WriteTinyScene("satmesh_eval_missing");
  try {
    EvaluateScene(dir.string(), (dir / "nope.ply").string());
    FAIL() << "expected an Error";
  } catch (const Error& err) {
    EXPECT_EQ(err.code(), ErrorCode::kNotFound);
    EXPECT_NE(std::string(err.what()).find("nope.ply"), std::string::npos);
  }
  fs::remove(dir / "initial" / "dsm.tif");
  EXPECT_THROW(EvaluateScene(dir.string(), (dir / "truth").string()), Error);
  fs::remove_all(dir);
}

TEST(SceneEvalOptions, DefaultsAreValid) { EXPECT_EQ(SceneEvalOptions{}.Check(), ""); }

// Error by height sigma: a flat truth and a result whose vertices sit sigma above it
// (sigma = 0.01 m x index): the deciles' median errors rise with sigma and equal it; the
// vertices no image saw (+inf) get their own bin.
TEST(ErrorBySigma, BinsTheResultsErrorByItsSigma) {
  TriangleMesh truth, result;
  const int n = 40;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      truth.vertices.emplace_back(float(i), float(j), 0.f);
      const float sigma = 0.001f * float(j * (n + 1) + i);
      result.vertices.emplace_back(float(i), float(j), sigma);
      result.height_sigma.push_back(i == n ? std::numeric_limits<float>::infinity() : sigma);
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      truth.faces.emplace_back(a, a + 1, a + n + 2);
      truth.faces.emplace_back(a, a + n + 2, a + n + 1);
    }
  result.faces = truth.faces;
  const auto bins = ErrorBySigma(result, truth, -1, n + 1, -1, n + 1);
  ASSERT_EQ(bins.size(), 11u);
  for (size_t b = 0; b < 10; ++b) {
    EXPECT_GT(bins[b].vertices, 150u);
    EXPECT_GE(bins[b].median_error_m, bins[b].sigma_min_m - 1e-4);
    EXPECT_LE(bins[b].median_error_m, bins[b].sigma_max_m + 1e-4);
    if (b > 0) {
      EXPECT_GT(bins[b].median_error_m, bins[b - 1].median_error_m);
    }
  }
  EXPECT_EQ(bins[10].vertices, size_t(n + 1));
  EXPECT_TRUE(std::isinf(bins[10].sigma_min_m));
}

// The views of a generated scene: at the AOI's centre each image's line of sight (from its
// RPC) is the direction to the satellite that the generator measured on its camera
// (scene.json's zenith and azimuth), within the CRS's grid convergence (0.33 deg here);
// a point far outside every image gets none; the truth against itself finds every facade
// sample two views see. The tiny city's tri-stereo is 3-13 deg off nadir: two of its
// views see few walls at the 0.1 cosine.
TEST(SceneViewDirections, LinesOfSightAreTheCamerasAndTheTruthFindsItsSeenFacades) {
  const synth::SynthOptions o = testing::TinySceneOptions();
  const fs::path dir = fs::temp_directory_path() / ("satmesh_eval_views_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const synth::SynthResult scene = synth::GenerateScene(dir.string(), o);
  const std::vector<std::string> images = SceneImages((dir / "images").string());
  ASSERT_EQ(images.size(), scene.views.size());
  const ViewDirectionsFn views = SceneViewDirections(images, o.crs);
  const Eigen::Vector3d lon_lat_h(o.center_lon_lat.x(), o.center_lon_lat.y(), o.base_height_m);
  const Eigen::Vector3d centre = CrsTransform(kWgs84Geographic3D, o.crs).Apply(lon_lat_h);
  const Eigen::Vector3d far_away = centre + Eigen::Vector3d(20000, 0, 0);
  const ViewDirections d = views({centre, far_away});
  ASSERT_EQ(d.size(), images.size());
  for (size_t v = 0; v < d.size(); ++v) {
    const double z = scene.views[v].zenith_deg * M_PI / 180, a = scene.views[v].azimuth_deg * M_PI / 180;
    const Eigen::Vector3d expected(std::sin(z) * std::sin(a), std::sin(z) * std::cos(a), std::cos(z));
    const double angle_deg = std::acos(std::min(1.0, d[v][0].cast<double>().dot(expected))) * 180 / M_PI;
    EXPECT_LT(angle_deg, 0.4) << images[v];
    EXPECT_GT(scene.views[v].zenith_deg, 2.0);  // a meaningful azimuth
    EXPECT_TRUE(d[v][1].isZero()) << images[v];
  }
  const SceneEvaluation e = EvaluateScene(dir.string(), (dir / "truth" / "mesh.ply").string());
  const Mesh3dScores& seen = e.result.mesh3d.seen_facade;
  ASSERT_FALSE(seen.thresholds_m.empty());
  EXPECT_GT(seen.num_truth_samples, 20u);
  EXPECT_LT(seen.num_truth_samples, e.result.mesh3d.facade.num_truth_samples);
  EXPECT_GT(seen.completeness[0], 0.999);
  EXPECT_EQ(e.initial.mesh3d.seen_facade.num_truth_samples, seen.num_truth_samples);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace satmesh
