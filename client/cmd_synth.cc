// satmesh synth: writes a synthetic satellite scene directory (see core/synth/scene_writer.h).
#include <spdlog/spdlog.h>

#include <cstdio>

#include "client/args.h"
#include "client/command.h"
#include "core/synth/scene_writer.h"

namespace satmesh::cli {
namespace {

int RunSynth(const std::vector<std::string>& argv) {
  const Args args(argv, {"help", "no-preview", "no-trees"});
  if (args.Has("help")) {
    std::printf(
        "usage: satmesh synth --out DIR [--preset small|default|large] [--seed N]\n"
        "                     [--views N] [--rpc-bias-px SIGMA] [--no-trees] [--no-preview]\n"
        "Writes images/*.tif (UInt16, RPC), truth/, initial/dsm.tif, scene.json, job.json,\n"
        "preview.png.\n");
    return kExitOk;
  }
  const std::string out = args.Require("out");
  const int seed = args.GetInt("seed", 1);
  SATMESH_CHECK(seed >= 0, ErrorCode::kInvalidArgument, "option --seed must be >= 0");
  synth::SynthOptions options = synth::SynthPreset(args.GetOr("preset", "small"), uint32_t(seed));
  options.num_views = args.GetInt("views", options.num_views);
  options.rpc_bias_sigma_px = args.GetDouble("rpc-bias-px", 0.0);
  if (args.Has("no-trees")) options.city.trees = false;
  if (args.Has("no-preview")) options.write_preview = false;
  const std::string why = options.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, why);
  Progress progress;
  progress.on_progress = [](double f, const std::string& stage) {
    spdlog::debug("synth {:.0f}% {}", 100 * f, stage);
  };
  const synth::SynthResult r = synth::GenerateScene(out, options, progress);
  std::printf("scene %s: preset %s seed %d, %d buildings, %zu faces, %zu views\n", out.c_str(),
              options.preset.c_str(), seed, r.num_buildings, r.num_faces, r.views.size());
  for (const auto& v : r.views)
    std::printf("  %s %dx%d off-nadir %.1f az %.1f gsd %.3f m  rpc fit max %.5f px  ray %.5f px\n",
                v.image.c_str(), v.width, v.height, v.off_nadir_deg, v.azimuth_deg, v.gsd_m,
                v.rpc_fit_max_half_step_px, v.ray_grid_error_px);
  std::printf("pairs: %zu selected by the refinement's rule (window %g-%g deg, cap %d per image), "
              "%d view pairs inside the window\n",
              r.pairs.size(), options.min_pair_angle_deg, options.max_pair_angle_deg,
              options.max_pairs_per_image, r.candidate_pairs);
  std::printf("initial DSM on roofs (%zu cells): NMAD %.3f m, p68 %.3f m, holes %.1f%%\n",
              r.num_roof_cells, r.initial_roof_nmad_m, r.initial_roof_p68_m,
              100 * r.initial_hole_fraction);
  std::printf("timings:");
  for (const auto& [stage, s] : r.timings_s) std::printf(" %s %.2fs", stage.c_str(), s);
  std::printf("  total %.2fs\n", r.total_s);
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("synth", "generate a synthetic satellite scene (images, RPCs, truth)",
                         RunSynth);

}  // namespace satmesh::cli
