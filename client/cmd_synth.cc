// satmesh synth: writes a synthetic satellite scene directory (see core/synth/scene_writer.h).
#include <spdlog/spdlog.h>

#include <cstdio>
#include <cstdlib>

#include "client/args.h"
#include "client/command.h"
#include "core/image/acquisition_info.h"
#include "core/synth/scene_writer.h"

namespace satmesh::cli {
namespace {

int RunSynth(const std::vector<std::string>& argv) {
  const Args args(argv, {"help", "no-preview", "no-trees"});
  if (args.Has("help")) {
    std::printf(
        "usage: satmesh synth --out DIR [--preset small|default|large] [--seed N]\n"
        "                     [--views stereo|tristereo|multidate|jax] [--num-views N]\n"
        "                     [--gsd M] [--size-m M] [--rpc-bias-px SIGMA] [--no-trees]\n"
        "                     [--convergence-deg MIN,MAX] [--initial-dsm noisy|sharp]\n"
        "                     [--no-preview]\n"
        "Writes images/*.tif (UInt16, RPC, IMD acquisition metadata), truth/, initial/dsm.tif,\n"
        "scene.json, job.json, preview.png.\n"
        "  --preset P       scene size: small (72 m, for tests), default (300 m), large (750 m)\n"
        "  --views C        the collection, as satellites acquire them (default: small tristereo,\n"
        "                   default multidate, large jax):\n"
        "                     stereo     2 views of one pass, along track, converging 15-35 deg,\n"
        "                                across-track roll 0-15 deg, one sun\n"
        "                     tristereo  3 views of one pass: fore / near-nadir / aft, each outer\n"
        "                                view 6-15 deg from the middle one, one sun\n"
        "                     multidate  6 passes on different dates: azimuth anywhere, off-nadir\n"
        "                                5-35 deg, the sun of each date, ~1 px RPC bias per image\n"
        "                     jax        multidate with 26 views (the JAX-like archive)\n"
        "  --num-views N    number of passes of multidate/jax, [2, 64]\n"
        "  --gsd M          ground sample distance and grid cell, m (e.g. 0.3, 0.5; default 0.3)\n"
        "  --size-m M       side of the square AOI, m (default: the preset's)\n"
        "  --rpc-bias-px S  per-image RPC bias sigma, px (default: 1 for multidate/jax, 0 for one pass)\n"
        "  --convergence-deg MIN,MAX  one pass: the range the convergence is drawn from (stereo:\n"
        "                   the pair's, default 15,35; tristereo: each outer view's with the middle\n"
        "                   one, default 6,15); e.g. 7,12 a Pleiades narrow pair, 30,45 WorldView\n"
        "  --initial-dsm D  the initial DSM's errors: noisy (default: edge fattening, blur,\n"
        "                   correlated and per-cell noise, blobs, holes; ~0.3 cell of noise at\n"
        "                   one cell at 0.5 m) or sharp (no blur, per-cell noise 0.05 m: as the\n"
        "                   Pleiades triplet's s2p DSM, 0.05 m at 0.5 m cells)\n");
    return kExitOk;
  }
  const std::string out = args.Require("out");
  const int seed = args.GetInt("seed", 1);
  SATMESH_CHECK(seed >= 0, ErrorCode::kInvalidArgument, "option --seed must be >= 0");
  synth::SynthOptions options = synth::SynthPreset(args.GetOr("preset", "small"), uint32_t(seed));
  if (args.Has("views")) {
    const std::string name = args.Require("views");
    const auto acquisition = synth::ParseAcquisition(name);
    SATMESH_CHECK(acquisition.has_value(), ErrorCode::kInvalidArgument,
                  "option --views: unknown collection '" + name + "' (expected stereo, tristereo, multidate or jax)");
    synth::SetAcquisition(&options, *acquisition);
  }
  if (args.Has("num-views")) {
    const auto a = options.views.acquisition;
    SATMESH_CHECK(a == synth::Acquisition::kMultiDate || a == synth::Acquisition::kJax,
                  ErrorCode::kInvalidArgument,
                  "option --num-views applies to multidate and jax (" + synth::AcquisitionName(a) +
                      " has a fixed number of views)");
    options.views.num_views = args.GetInt("num-views", options.views.num_views);
  }
  if (args.Has("convergence-deg")) {
    const std::string range = args.Require("convergence-deg");
    char* end = nullptr;
    const double lo = std::strtod(range.c_str(), &end);
    bool parsed = end != range.c_str() && *end == ',';
    const char* second = parsed ? end + 1 : end;
    const double hi = std::strtod(second, &end);
    parsed = parsed && end != second && *end == '\0';
    SATMESH_CHECK(parsed, ErrorCode::kInvalidArgument,
                  "option --convergence-deg: expected MIN,MAX in degrees, got '" + range + "'");
    const auto a = options.views.acquisition;
    SATMESH_CHECK(a == synth::Acquisition::kStereo || a == synth::Acquisition::kTriStereo,
                  ErrorCode::kInvalidArgument,
                  "option --convergence-deg applies to one pass, stereo and tristereo (" +
                      synth::AcquisitionName(a) + " draws its views from the off-nadir range)");
    if (a == synth::Acquisition::kStereo) {
      options.views.stereo_min_convergence_deg = lo;
      options.views.stereo_max_convergence_deg = hi;
    } else {
      options.views.tristereo_min_convergence_deg = lo;
      options.views.tristereo_max_convergence_deg = hi;
    }
  }
  options.gsd_m = args.GetDouble("gsd", options.gsd_m);
  options.city.aoi_size_m = args.GetDouble("size-m", options.city.aoi_size_m);
  options.rpc_bias_sigma_px = args.GetDouble("rpc-bias-px", options.rpc_bias_sigma_px);
  if (args.Has("initial-dsm")) {
    const std::string dsm = args.Require("initial-dsm");
    SATMESH_CHECK(dsm == "noisy" || dsm == "sharp", ErrorCode::kInvalidArgument,
                  "option --initial-dsm: expected noisy or sharp, got '" + dsm + "'");
    if (dsm == "sharp") options.initial.white_noise_m = 0.05, options.initial.blur_sigma_m = 0;
  }
  if (args.Has("no-trees")) options.city.trees = false;
  if (args.Has("no-preview")) options.write_preview = false;
  const std::string why = options.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, why);
  Progress progress;
  progress.on_progress = [](double f, const std::string& stage) {
    spdlog::debug("synth {:.0f}% {}", 100 * f, stage);
  };
  const synth::SynthResult r = synth::GenerateScene(out, options, progress);
  std::printf("scene %s: preset %s seed %d, %d buildings, %zu faces, %zu views (%s), gsd %g m\n",
              out.c_str(), options.preset.c_str(), seed, r.num_buildings, r.num_faces, r.views.size(),
              synth::AcquisitionName(options.views.acquisition).c_str(), options.gsd_m);
  for (const auto& v : r.views)
    std::printf("  %s %dx%d pass %d %s off-nadir %.1f az %.1f gsd %.3f m sun el %.1f az %.1f  "
                "bias (%.2f, %.2f) px  rpc fit max %.5f px  ray %.5f px\n",
                v.image.c_str(), v.width, v.height, v.pass, FormatIso8601Utc(v.acquisition_unix_s).substr(0, 19).c_str(),
                v.off_nadir_deg, v.azimuth_deg, v.gsd_m, v.sun.elevation_deg, v.sun.azimuth_deg,
                v.bias_col_row_px.x(), v.bias_col_row_px.y(), v.rpc_fit_max_half_step_px, v.ray_grid_error_px);
  for (size_t i = 0; r.views.size() <= 6 && i < r.views.size(); ++i)  // convergence angles
    for (size_t j = i + 1; j < r.views.size(); ++j)
      std::printf("%s%zu-%zu %.1f", i + j == 1 ? "convergence (deg):" : ",", i, j,
                  synth::ViewIntersectionAngleDeg({r.views[i].off_nadir_deg, r.views[i].azimuth_deg},
                                                  {r.views[j].off_nadir_deg, r.views[j].azimuth_deg}));
  if (r.views.size() <= 6) std::printf("\n");
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
