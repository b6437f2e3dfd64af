// satmesh demo: synthetic scene -> refine -> evaluation table (README command 1).
#include <cstdio>
#include <filesystem>

#include "client/args.h"
#include "client/command.h"
#include "client/eval_pictures.h"
#include "client/eval_report_format.h"
#include "client/refine_runner.h"
#include "core/eval/scene_eval.h"
#include "core/synth/scene_writer.h"

namespace satmesh::cli {
namespace {

int RunDemo(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help")) {
    std::printf(
        "usage: satmesh demo [--preset small|default] [--seed N] [--out DIR] [--set key=value ...]\n"
        "  Generates a synthetic scene, refines it and prints initial vs refined metrics.\n");
    return kExitOk;
  }
  const std::string out = args.GetOr("out", "satmesh-demo");
  const std::string scene_dir = (std::filesystem::path(out) / "scene").string();
  const std::string result_dir = (std::filesystem::path(out) / "result").string();
  std::printf("== 1/3 synthetic scene -> %s\n", scene_dir.c_str());
  const auto options = synth::SynthPreset(args.GetOr("preset", "small"), uint32_t(args.GetInt("seed", 1)));
  synth::GenerateScene(scene_dir, options);
  std::printf("== 2/3 refine -> %s\n", result_dir.c_str());
  const auto outputs = RunJobFile((std::filesystem::path(scene_dir) / "job.json").string(),
                                  result_dir, args.GetAll("set"));
  for (const auto& level : outputs.refine.levels) {
    std::printf("level %d: %7d faces  mean ZNCC %.4f -> %.4f  (%.1f s)\n", level.level,
                level.num_faces, level.mean_zncc.front(), level.mean_zncc.back(), level.level_s);
  }
  std::printf("== 3/3 evaluation (initial DSM vs refined mesh, against the ground truth)\n");
  const SceneEvaluation evaluation = EvaluateScene(scene_dir, outputs.mesh_path);
  std::printf("%s\n", FormatSceneEvaluation(evaluation).c_str());
  const std::string pictures = (std::filesystem::path(out) / "pictures").string();
  std::printf("== pictures\n");
  for (const auto& path : WriteEvalPictures(scene_dir, result_dir, evaluation, pictures))
    std::printf("%s\n", path.c_str());
  for (const char* file : {"preview.png", "convergence.png"})
    if (std::filesystem::exists(std::filesystem::path(result_dir) / file))
      std::printf("%s\n", (std::filesystem::path(result_dir) / file).string().c_str());
  std::printf("viewer: python3 -m http.server -d %s, then open http://127.0.0.1:8000/viewer.html\n",
              result_dir.c_str());
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("demo", "synthetic scene -> refine -> before/after metrics", RunDemo);

}  // namespace satmesh::cli
