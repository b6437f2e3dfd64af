// satmesh refine JOB.json --out DIR [--set key=value ...]
#include <cstdio>
#include <string>
#include <vector>

#include "client/args.h"
#include "client/command.h"
#include "client/refine_runner.h"
#include "core/tiling/job_spec.h"

namespace satmesh::cli {
namespace {

// The options of a table (RefineOptionTable(), TilingOptionTable()): the names --set takes.
template <typename Info>
void PrintOptions(const char* title, const std::vector<Info>& table) {
  std::printf("  %s\n", title);
  for (const Info& option : table) {
    std::printf("    %-26s %-6s %-10s %.*s\n", std::string(option.name).c_str(),
                OptionValueText(option.Default()).c_str(), option.RangeText().c_str(),
                int(option.help.size()), option.help.data());
  }
}

int RunRefine(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || args.positionals().size() != 1) {
    std::printf(
        "usage: satmesh refine JOB.json --out DIR [--memory-budget MB] [--set key=value ...]\n"
        "  Refines the job's initial surface tile by tile; writes DIR/mesh.ply, DIR/dsm.tif,\n"
        "  DIR/tiles/<x>_<y>.glb, DIR/tileset.json and DIR/metrics.json.\n"
        "  --set overrides an option of proto/job.schema.json (e.g. --set levels=2,\n"
        "  --set tiling.size_m=100 --set tiling.workers=2).\n"
        "  --memory-budget MB: one worker's peak memory (tiling.memory_budget_mb; default a\n"
        "  quarter of the machine's memory / workers): a job without tiling is cut into\n"
        "  tiles that fit it; a tile that cannot fit is refused, naming budget and need.\n");
    PrintOptions("Refinement options (--set NAME=VALUE, or the job's \"options\"):",
                 RefineOptionTable());
    PrintOptions("Tiling options (--set tiling.NAME=VALUE, or the job's \"tiling\"):",
                 TilingOptionTable());
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  std::vector<std::string> overrides = args.GetAll("set");
  if (const auto budget = args.Get("memory-budget")) overrides.push_back("tiling.memory_budget_mb=" + *budget);
  const auto outputs = RunJobFile(args.positionals()[0], args.Require("out"), overrides);
  for (const auto& level : outputs.refine.levels) {
    if (level.mean_zncc.empty()) continue;
    std::printf("level %d%s: %7d faces  mean ZNCC %.4f -> %.4f  (%.1f s)\n", level.level,
                level.crease_pass ? " (creases)" : "", level.num_faces, level.mean_zncc.front(), level.mean_zncc.back(), level.level_s);
  }
  for (const auto& tile : outputs.tiles) {
    if (!tile.ok) {
      std::printf("tile %-7s FAILED: %s\n", tile.name.c_str(), tile.error.c_str());
      continue;
    }
    const auto& zncc = tile.refine.levels.back().mean_zncc;  // the finest level
    std::printf("tile %-7s %2zu views  %8zu faces  level-0 ZNCC %.4f -> %.4f  %.1f s  %.0f MB images"
                "  peak est. %.0f MB, process %.0f MB\n",
                tile.name.c_str(), tile.view_names.size(), tile.core_faces,
                zncc.empty() ? 0.0 : zncc.front(), zncc.empty() ? 0.0 : zncc.back(), tile.refine_s,
                tile.image_mb, tile.estimated_peak_mb, tile.peak_rss_mb);
  }
  const auto& seams = outputs.assembly.seams_total;
  if (seams.cells > 0)
    std::printf("seams: %d cells, |step| median %.3f m, p95 %.3f m, max %.3f m\n", seams.cells,
                seams.median_abs_m, seams.p95_abs_m, seams.max_abs_m);
  std::printf("%d/%zu tiles ok, %d workers, %.1f s, peak RSS %.0f MB\n", outputs.assembly.tiles_ok,
              outputs.tiles.size(), outputs.workers, outputs.total_s, outputs.peak_rss_mb);
  return outputs.assembly.tiles_failed == 0 ? kExitOk : kExitFailure;
}

}  // namespace

SATMESH_REGISTER_COMMAND("refine", "refine a job's surface (in-process, tiled)", RunRefine);

}  // namespace satmesh::cli
