// Jobs and their meshes on a tiny synthetic scene (36 m, tri-stereo; generated once):
// outputs without debris on a many-tile job, jobs that start from a mesh (the scene's
// truth mesh), chaining a result, and bad meshes refused naming file and problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "core/dsm/dsm.h"
#include "core/mesh/mesh_clean.h"
#include "core/mesh/mesh_io.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/job.h"
#include "proto/job_spec_json.h"
#include "tests/scratch_dir.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

class MeshJob : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    synth::SynthOptions o = synth::SynthPreset("small", 3);
    o.city.aoi_size_m = 36;
    o.city.ground_margin_m = 45;
    o.city.building_margin_m = 5;
    o.city.street_pitch_m = 40;
    o.render.supersample = 1;
    o.write_preview = false;
    scene_ = (fs::temp_directory_path() / ("mesh_job_scene_" + std::to_string(::getpid()))).string();
    fs::remove_all(scene_);
    synth::GenerateScene(scene_, o);
  }
  static void TearDownTestSuite() { fs::remove_all(scene_); }

  // Cheap refinement: one coarse level, few iterations.
  static JobSpec Spec() {
    JobSpec spec = proto::ReadJobFile(scene_ + "/job.json");
    spec.refine.levels = 1;
    spec.refine.iterations_per_level = 3;
    spec.tiling.overlap_m = 3;
    spec.tiling.workers = 2;
    return spec;
  }
  static std::string OutDir(const std::string& name) {
    const auto dir = fs::temp_directory_path() / ("mesh_job_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    testing::RemoveAtExit(dir);
    return dir.string();
  }
  // Every mesh a job wrote: mesh.ply and each tile's .ply and .glb.
  static void ExpectNoDebris(const std::string& out) {
    EXPECT_EQ(FindDebris(ReadMesh(out + "/mesh.ply")).ToString(), MeshDebris{}.ToString())
        << "mesh.ply";
    for (const auto& entry : fs::directory_iterator(fs::path(out) / "tiles")) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".ply" && ext != ".glb") continue;
      EXPECT_EQ(FindDebris(ReadMesh(entry.path().string())).ToString(), MeshDebris{}.ToString())
          << entry.path();
    }
  }
  // The scene's area (the initial DSM's extent), where the images look.
  static std::vector<Eigen::Vector2d> SceneAoi() {
    const Dsm dsm = ReadDsm(scene_ + "/initial/dsm.tif");
    const double x0 = dsm.geo_transform[0], y1 = dsm.geo_transform[3];
    const double x1 = x0 + dsm.width * dsm.geo_transform[1], y0 = y1 + dsm.height * dsm.geo_transform[5];
    return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  }
  static std::string scene_;
};
std::string MeshJob::scene_;

TEST_F(MeshJob, ManyTilesFromTheDsmLeaveNoDebris) {
  JobSpec spec = Spec();
  spec.tiling.tile_size_m = 9;  // 4 x 4 tiles
  const std::string out = OutDir("debris_dsm");
  const JobOutputs o = RunJob(spec, out);
  ASSERT_EQ(o.tiles.size(), 16u);
  EXPECT_EQ(o.assembly.tiles_ok, 16);
  ExpectNoDebris(out);
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

// The median |refined - truth| over the truth DSM's cells where both have a surface.
double MedianAbsDsmError(const std::string& result_dsm, const std::string& truth_dsm) {
  const Dsm result = ReadDsm(result_dsm), truth = ReadDsm(truth_dsm);
  std::vector<double> diffs;
  for (int j = 0; j < truth.height; ++j)
    for (int i = 0; i < truth.width; ++i) {
      const double x = truth.geo_transform[0] + (i + 0.5) * truth.geo_transform[1];
      const double y = truth.geo_transform[3] + (j + 0.5) * truth.geo_transform[5];
      const int ri = int(std::floor((x - result.geo_transform[0]) / result.geo_transform[1]));
      const int rj = int(std::floor((y - result.geo_transform[3]) / result.geo_transform[5]));
      if (ri < 0 || rj < 0 || ri >= result.width || rj >= result.height) continue;
      const float a = result.at(ri, rj), b = truth.at(i, j);
      if (std::isfinite(a) && std::isfinite(b)) diffs.push_back(std::abs(double(a) - b));
    }
  if (diffs.empty()) return INFINITY;
  std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
  return diffs[diffs.size() / 2];
}

TEST_F(MeshJob, StartsFromTheTruthMeshAndKeepsIt) {
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.initial_mesh.path = scene_ + "/truth/mesh.ply";
  spec.tiling.tile_size_m = 18;  // 2 x 2 over the images' area (the mesh has 45 m more ground)
  spec.aoi.polygon = SceneAoi();
  const std::string out = OutDir("truth_start");
  const JobOutputs o = RunJob(spec, out);
  EXPECT_EQ(o.assembly.tiles_failed, 0);
  ASSERT_GE(o.tiles.size(), 4u);
  for (const auto& t : o.tiles) EXPECT_TRUE(t.ok) << t.name << ": " << t.error;
  // The grid: the images' GSD (the scene's 0.3 m) over the mesh.
  EXPECT_NEAR(o.plan.dsm.geo_transform[1], 0.3, 0.03);
  ExpectNoDebris(out);
  EXPECT_LT(MedianAbsDsmError(o.dsm_path, scene_ + "/truth/dsm.tif"), 0.1);
}

}  // namespace
}  // namespace satmesh
