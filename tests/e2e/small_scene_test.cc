// End to end on a small synthetic scene: synth -> job file -> refine (the CLI's path) ->
// evaluation against the ground truth. Tolerance bands from the acceptance
// criteria (roofs NMAD <= 0.6x, perc-68 <= 0.7x of the initial DSM's; facade
// completeness at 0.5 m above the initial's; mean ZNCC rising at every level).
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
  EXPECT_LE(roof_result.nmad_m, 0.6 * roof_initial.nmad_m);
  EXPECT_LE(roof_result.perc68_m, 0.7 * roof_initial.perc68_m);
  EXPECT_GT(e.result.mesh3d.facade.completeness[1], 1.2 * e.initial.mesh3d.facade.completeness[1]);
  EXPECT_GT(e.result.mesh3d.all.fscore[1], e.initial.mesh3d.all.fscore[1]);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace satmesh
