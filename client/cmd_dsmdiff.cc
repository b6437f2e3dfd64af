// satmesh dsmdiff: 2.5D differences of a DSM against a reference DSM on the same grid
// (e.g. a refined dsm.tif against the initial DSM when there is no ground truth).
#include <cstdio>

#include "client/args.h"
#include "client/command.h"
#include "core/eval/dsm_metrics.h"

namespace satmesh::cli {
namespace {

void PrintMetrics(const char* name, const DsmMetrics& m) {
  std::printf("%-9s cells %8zu  valid %5.1f%%  median %+7.3f m  NMAD %6.3f m  perc68 %6.3f m  "
              "RMSE(<3m) %6.3f m  <1m %5.1f%%  <3m %5.1f%%\n",
              name, m.num_cells, m.num_cells ? 100.0 * m.num_valid / m.num_cells : 0.0, m.median_m,
              m.nmad_m, m.perc68_m, m.rmse_m, 100 * m.completeness_1m, 100 * m.completeness);
}

int RunDsmDiff(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || !args.Has("result") || !args.Has("reference")) {
    std::printf(
        "usage: satmesh dsmdiff --result DSM.tif --reference DSM.tif [--max-shift-m D]\n"
        "  Residuals result - reference on every cell where the reference is valid, raw and\n"
        "  after an XY+Z alignment (align3d style). The grids must match.\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  DsmEvalOptions options;
  options.align.max_shift_m = args.GetDouble("max-shift-m", 3.0);
  const Dsm result = ReadDsm(args.Require("result"));
  const Dsm reference = ReadDsm(args.Require("reference"));
  const DsmEvaluation e = EvaluateDsm(result, reference, /*mask=*/{}, options);
  PrintMetrics("raw", e.all_raw);
  PrintMetrics("aligned", e.all_aligned);
  std::printf("alignment: dx %+.2f m, dy %+.2f m, dz %+.3f m\n", e.alignment.dx_m,
              e.alignment.dy_m, e.alignment.dz_m);
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("dsmdiff", "DSM vs reference DSM differences (same grid)", RunDsmDiff);

}  // namespace satmesh::cli
