// End to end on a small synthetic scene: synth -> job file -> refine (the CLI's path) ->
// evaluation against the ground truth. The small preset is a Pléiades-like tri-stereo
// (near-nadir: walls are seen at 6-15 degrees at most). Tolerance bands from the view-set
// issue's acceptance criteria for every collection: roofs NMAD and perc-68 <= 0.8x the
// initial DSM's, facade completeness at 0.5 m and the 3D F-score above the initial's;
// mean ZNCC rising at every level. (The bands of 0.6x and +20% facades were set on a
// 4-view scene planned for the old pair rule, with walls seen up to 35 degrees.)
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "core/eval/scene_eval.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/job.h"
#include "proto/job_spec_json.h"

namespace satmesh {
namespace {

// A fresh directory `name`_<pid> under the temp dir with the small preset's city (seed 1)
// as one stereo pair at 0.5 m in scene/ (`synth --preset small --views stereo --gsd 0.5`).
std::filesystem::path SmallStereoScene(const std::string& name) {
  const auto dir =
      std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  synth::SynthOptions options = synth::SynthPreset("small", /*seed=*/1);
  synth::SetAcquisition(&options, synth::Acquisition::kStereo);
  options.gsd_m = 0.5;
  options.write_preview = false;
  synth::GenerateScene((dir / "scene").string(), options);
  return dir;
}

// Runs `spec` into `result` (one tile, which must succeed) and evaluates it on `scene`.
void RunOneTileJob(const std::string& scene, const JobSpec& spec, const std::string& result,
                   SceneEvaluation* eval, size_t* levels = nullptr) {
  const JobOutputs outputs = RunJob(spec, result);
  ASSERT_EQ(outputs.tiles.size(), 1u);
  ASSERT_TRUE(outputs.tiles[0].ok) << outputs.tiles[0].error;
  if (levels) *levels = outputs.tiles[0].refine.levels.size();
  *eval = EvaluateScene(scene, outputs.mesh_path);
}

TEST(EndToEnd, SmallSyntheticSceneRefinesBeyondTheInitialDsm) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("satmesh_e2e_small_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::string scene = (dir / "scene").string(), result = (dir / "result").string();
  synth::SynthOptions options = synth::SynthPreset("small", /*seed=*/1);
  options.write_preview = false;
  synth::GenerateScene(scene, options);

  const JobSpec spec = proto::ReadJobFile(scene + "/job.json");
  const JobOutputs outputs = RunJob(spec, result);
  ASSERT_FALSE(outputs.tiles.empty());
  for (const auto& tile : outputs.tiles) {
    ASSERT_TRUE(tile.ok) << tile.name << ": " << tile.error;
    for (const auto& level : tile.refine.levels)
      EXPECT_GT(level.mean_zncc.back(), level.mean_zncc.front()) << "level " << level.level;
  }

  const SceneEvaluation e = EvaluateScene(scene, outputs.mesh_path);
  const DsmMetrics& roof_initial = e.initial.dsm.mask_raw;
  const DsmMetrics& roof_result = e.result.dsm.mask_raw;
  EXPECT_LE(roof_result.nmad_m, 0.8 * roof_initial.nmad_m);
  EXPECT_LE(roof_result.perc68_m, 0.8 * roof_initial.perc68_m);
  EXPECT_GT(e.result.mesh3d.facade.completeness[1], e.initial.mesh3d.facade.completeness[1]);
  EXPECT_GT(e.result.mesh3d.all.fscore[1], e.initial.mesh3d.all.fscore[1]);
  std::filesystem::remove_all(dir);
}

// One stereo pair at 0.5 m (`synth --preset small --views stereo --gsd 0.5`): the DSM's
// sloped walls that the pair does not move hang plumb under their tops (plumb_walls.h).
// Against the same job with the hang off: the true walls' offset median from the result
// falls 0.64 -> 0.42 m, facades @0.5 m 30.9 -> 42.3%, F 53.7 -> 58.3, roofs 0.250 -> 0.252
// m (session 46); the bands below hold half of that.
TEST(EndToEnd, OneStereoPairsWallsHangPlumbUnderTheirTops) {
  const auto dir = SmallStereoScene("satmesh_e2e_plumb");
  const std::string scene = (dir / "scene").string();
  SceneEvaluation eval[2];  // hang off, on
  for (int on = 0; on < 2; ++on) {
    JobSpec spec = proto::ReadJobFile(scene + "/job.json");
    spec.refine.plumb_walls = on;
    ASSERT_NO_FATAL_FAILURE(
        RunOneTileJob(scene, spec, (dir / ("result_" + std::to_string(on))).string(), &eval[on]));
  }
  const Mesh3dMetrics &off = eval[0].result.mesh3d, &on = eval[1].result.mesh3d;
  EXPECT_LT(on.facade_offset.median_m, off.facade_offset.median_m - 0.1);
  EXPECT_GT(on.facade.completeness[1], off.facade.completeness[1] + 0.05);
  EXPECT_GT(on.all.fscore[1], off.all.fscore[1] + 0.02);
  EXPECT_LT(eval[1].result.dsm.mask_raw.nmad_m, 1.03 * eval[0].result.dsm.mask_raw.nmad_m);
  std::filesystem::remove_all(dir);
}

// A DSM whose walls are in place (the generator's true DSM as the start: a LiDAR or city
// model's DSM) and one stereo pair at 0.5 m. By default the refinement takes it for a stereo
// DSM (block averages, walls hung and moved inward) and loses most of its facades; declared
// trusted (trusted_initial) it keeps them and its roofs (never worse than the start by more
// than 2 points of facades and 3 of F). Measured (session 47): facades @0.5 m start / default
// / trusted 80.9 / 46.0 / 80.3%, F 85.2 / 64.7 / 82.5, roofs NMAD default / trusted 0.113 /
// 0.007 m.
TEST(EndToEnd, ATrustedDsmWhoseWallsAreInPlaceKeepsThem) {
  const auto dir = SmallStereoScene("satmesh_e2e_trusted");
  const std::string scene = (dir / "scene").string();
  std::filesystem::copy_file(scene + "/truth/dsm.tif", scene + "/initial/dsm.tif",
                             std::filesystem::copy_options::overwrite_existing);
  SceneEvaluation eval[2];  // default, trusted
  for (int trusted = 0; trusted < 2; ++trusted) {
    JobSpec spec = proto::ReadJobFile(scene + "/job.json");
    spec.refine.trusted_initial = trusted;
    size_t levels = 0;
    ASSERT_NO_FATAL_FAILURE(RunOneTileJob(scene, spec,
                                          (dir / ("result_" + std::to_string(trusted))).string(),
                                          &eval[trusted], &levels));
    EXPECT_EQ(levels, 1u);  // one pair at 0.5 m: level 0 once, trusted or not
  }
  const Mesh3dMetrics &start = eval[1].initial.mesh3d, &plain = eval[0].result.mesh3d,
                      &trusted = eval[1].result.mesh3d;
  std::printf(
      "facades @0.5 m start / default / trusted %.1f / %.1f / %.1f%%, F %.1f / %.1f / "
      "%.1f, roofs NMAD default / trusted %.3f / %.3f m\n",
      100 * start.facade.completeness[1], 100 * plain.facade.completeness[1],
      100 * trusted.facade.completeness[1], 100 * start.all.fscore[1], 100 * plain.all.fscore[1],
      100 * trusted.all.fscore[1], eval[0].result.dsm.mask_raw.nmad_m,
      eval[1].result.dsm.mask_raw.nmad_m);
  EXPECT_EQ(eval[1].initial.dsm.mask_raw.nmad_m, 0.0);  // the start is the truth
  EXPECT_GE(trusted.facade.completeness[1], start.facade.completeness[1] - 0.02);
  EXPECT_GE(trusted.all.fscore[1], start.all.fscore[1] - 0.03);
  EXPECT_LT(eval[1].result.dsm.mask_raw.nmad_m, 0.05);
  EXPECT_GT(trusted.facade.completeness[1], plain.facade.completeness[1] + 0.1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace satmesh
