// End to end on a small synthetic scene: synth -> job file -> refine (the CLI's path) ->
// evaluation against the ground truth. The small preset is a Pléiades-like tri-stereo
// (near-nadir: walls are seen at 6-15 degrees at most). Tolerance bands from the view-set
// issue's acceptance criteria for every collection: roofs NMAD and perc-68 <= 0.8x the
// initial DSM's, facade completeness at 0.5 m and the 3D F-score above the initial's;
// mean ZNCC rising at every level. (The bands of 0.6x and +20% facades were set on a
// 4-view scene planned for the old pair rule, with walls seen up to 35 degrees.)
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include <unistd.h>

#include "core/eval/scene_eval.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/job.h"
#include "proto/job_spec_json.h"

namespace satmesh {
namespace {

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

}  // namespace
}  // namespace satmesh
