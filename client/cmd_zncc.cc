// satmesh zncc: mean ZNCC (the refinement's photo-consistency) of given surfaces over given
// view pairs, without refining; e.g. a held-out view against the views that were used.
#include <cmath>
#include <cstdio>

#include "client/args.h"
#include "client/bench_support.h"
#include "client/command.h"
#include "core/refine/refine.h"
#include "core/refine/virtual_camera.h"

namespace satmesh::cli {
namespace {

// Intersection angle (deg) of two views' central viewing directions, as pair selection
// measures it.
double PairAngleDeg(const RefineInput& input, int a, int b) {
  Eigen::Vector3d d[2];
  for (int k = 0; k < 2; ++k) {
    const RefineView& v = input.views[k == 0 ? a : b];
    const int size = std::max(v.image.width, v.image.height);
    d[k] = VirtualCamera(v.rpc, input.frame, v.image.width, v.image.height, input.min_z - 1,
                         input.max_z + 1, size)
               .CentralDirection();
  }
  const double c = std::clamp(d[0].normalized().dot(d[1].normalized()), -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

int RunZncc(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || !args.Has("job") || !args.Has("mesh") || !args.Has("pairs")) {
    std::printf(
        "usage: satmesh zncc --job JOB.json --mesh MESH [--mesh MESH ...] --pairs I-J[,I-J...]\n"
        "                    [--level L] [--set key=value ...]\n"
        "  Mean ZNCC of each surface over the pairs (indices into the job's images, as the job\n"
        "  runner keeps them) at pyramid level L (default 0), with the job's ZNCC options. No\n"
        "  pair-angle filter. MESH: a mesh file (CRS from the file, else the initial DSM's), a\n"
        "  refine result directory (its mesh.ply), a DSM .tif, or 'initial' (the job's DSM).\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  const JobSpec spec = ReadJobWithOverrides(args.Require("job"), args.GetAll("set"));
  const TileInput input = PrepareJobInput(spec);
  const int num_views = int(input.refine.views.size());
  for (int v = 0; v < num_views; ++v)
    std::printf("view %d: %s (%dx%d window)\n", v, input.view_names[v].c_str(),
                input.refine.views[v].image.width, input.refine.views[v].image.height);
  const auto pairs = ParsePairs(args.Require("pairs"), num_views);
  for (const auto& [a, b] : pairs)
    std::printf("pair %d-%d: intersection angle %.2f deg\n", a, b, PairAngleDeg(input.refine, a, b));
  const int level = args.GetInt("level", 0);

  for (const std::string& path : args.GetAll("mesh")) {
    const TriangleMesh mesh = LoadMeshInFrame(path, spec, input.dsm_crs_wkt, input.refine.frame);
    std::printf("%s (%zu faces), level %d:", path.c_str(), mesh.num_faces(), level);
    for (const auto& pair : pairs) {
      const double zncc = MeasureMeanZncc(input.refine, mesh, {pair}, level, spec.refine);
      std::printf("  %d-%d %.4f", pair.first, pair.second, zncc);
    }
    if (pairs.size() > 1)
      std::printf("  all %.4f", MeasureMeanZncc(input.refine, mesh, pairs, level, spec.refine));
    std::printf("\n");
  }
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("zncc", "mean ZNCC of surfaces over view pairs (held-out checks)", RunZncc);

}  // namespace satmesh::cli
