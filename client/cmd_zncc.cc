// satmesh zncc: mean ZNCC (the refinement's photo-consistency) of given surfaces over given
// view pairs, without refining; e.g. a held-out view against the views that were used.
#include <cmath>
#include <cstdio>

#include "client/args.h"
#include "client/bench_support.h"
#include "client/command.h"
#include "core/refine/bias_estimation.h"
#include "core/refine/refine.h"
#include "core/refine/surface_comparison.h"
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
  const Args args(argv, {"help", "estimate-bias"});
  if (args.Has("help") || !args.Has("job") || !args.Has("mesh") || !args.Has("pairs")) {
    std::printf(
        "usage: satmesh zncc --job JOB.json --mesh MESH [--mesh MESH ...] --pairs I-J[,I-J...]\n"
        "                    [--level L] [--estimate-bias [--bias-pairs I-J,...]] [--set key=value ...]\n"
        "  Mean ZNCC of each surface over the pairs (indices into the job's images, as the job\n"
        "  runner keeps them) at pyramid level L (default 0), with the job's ZNCC options. No\n"
        "  pair-angle filter. MESH: a mesh file (CRS from the file, else the initial DSM's), a\n"
        "  refine result directory (its mesh.ply), a DSM .tif, 'initial' (the job's DSM) or\n"
        "  'initial-filled' (the job's DSM with its holes filled, as the refinement meshes it).\n"
        "  RPC biases: the job's images[].bias; --estimate-bias adds shifts estimated over the\n"
        "  job's INITIAL surface (as `satmesh bias`; pairs: the refinement's, or --bias-pairs),\n"
        "  so a held-out view is aligned to the initial surface, not to the measured ones.\n"
        "  Given several surfaces, also each one's mean over the windows every surface counts\n"
        "  (one support: a surface's own mean averages the windows it makes valid).\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  const JobSpec spec = ReadJobWithOverrides(args.Require("job"), args.GetAll("set"));
  TileInput input = PrepareJobInput(spec);
  const int num_views = int(input.refine.views.size());
  if (args.Has("estimate-bias")) {
    BiasOptions bias;
    bias.refine = spec.refine;
    ApplyViewBiases(args.Has("bias-pairs")
                        ? EstimateViewBiases(input.refine,
                                             ParsePairs(args.Require("bias-pairs"), num_views), bias)
                        : EstimateRefineBiases(input.refine, bias),
                    &input.refine);
  }
  for (int v = 0; v < num_views; ++v) {
    const RefineView& view = input.refine.views[v];
    std::printf("view %d: %s (%dx%d window), RPC bias %+.3f %+.3f px (col, row)\n", v,
                input.view_names[v].c_str(), view.image.width, view.image.height,
                view.rpc.bias().x(), view.rpc.bias().y());
  }
  const auto pairs = ParsePairs(args.Require("pairs"), num_views);
  for (const auto& [a, b] : pairs)
    std::printf("pair %d-%d: intersection angle %.2f deg\n", a, b, PairAngleDeg(input.refine, a, b));
  const int level = args.GetInt("level", 0);

  const std::vector<std::string> paths = args.GetAll("mesh");
  std::vector<TriangleMesh> meshes;
  for (const std::string& path : paths)
    meshes.push_back(LoadMeshInFrame(path, spec, input.dsm_crs_wkt, input.refine.frame));
  // One pass a surface gives both tables: each surface's mean over the windows it makes
  // valid, and (several surfaces) over the windows every surface counts, one support
  // (surface_comparison.h).
  const auto zncc = CommonWindowZncc(input.refine, meshes, pairs, level, spec.refine);
  const auto print_table = [&](bool common) {
    for (size_t s = 0; s < meshes.size(); ++s) {
      std::printf("%s (%zu faces), level %d%s:", paths[s].c_str(), meshes[s].num_faces(), level,
                  common ? ", common windows" : "");
      double sum = 0;
      long count = 0;
      for (size_t k = 0; k < pairs.size(); ++k) {
        const PairComparison& c = zncc[s][k];
        const double mean = common ? c.mean_zncc : c.own_mean_zncc;
        const long windows = common ? c.windows : c.own_windows;
        std::printf("  %d-%d %.4f", pairs[k].first, pairs[k].second, mean);
        sum += mean * double(windows);
        count += windows;
      }
      if (pairs.size() > 1) std::printf("  all %.4f", count > 0 ? sum / double(count) : 0.0);
      std::printf("\n");
    }
  };
  print_table(/*common=*/false);
  if (meshes.size() < 2) return kExitOk;
  std::printf("over the windows every surface counts:");
  for (size_t k = 0; k < pairs.size(); ++k)
    std::printf("  %d-%d %ld", pairs[k].first, pairs[k].second, zncc[0][k].windows);
  std::printf("\n");
  print_table(/*common=*/true);
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("zncc", "mean ZNCC of surfaces over view pairs (held-out checks)", RunZncc);

}  // namespace satmesh::cli
