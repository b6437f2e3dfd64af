// satmesh refine JOB.json --out DIR [--set key=value ...]
#include <cstdio>

#include "client/args.h"
#include "client/command.h"
#include "client/refine_runner.h"

namespace satmesh::cli {
namespace {

int RunRefine(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || args.positionals().size() != 1) {
    std::printf(
        "usage: satmesh refine JOB.json --out DIR [--set key=value ...]\n"
        "  Refines the job's initial surface; writes DIR/mesh.ply, DIR/dsm.tif, DIR/metrics.json.\n"
        "  --set overrides an option of proto/job.schema.json (e.g. --set levels=2).\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  const auto outputs = RunJobFile(args.positionals()[0], args.Require("out"), args.GetAll("set"));
  for (const auto& level : outputs.refine.levels) {
    std::printf("level %d: %7d faces  mean ZNCC %.4f -> %.4f  (%.1f s)\n", level.level,
                level.num_faces, level.mean_zncc.front(), level.mean_zncc.back(), level.level_s);
  }
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("refine", "refine a job's surface (in-process)", RunRefine);

}  // namespace satmesh::cli
