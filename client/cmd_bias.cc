// satmesh bias: per-image RPC bias shifts estimated over the job's initial surface (the
// correction `estimate_bias` applies before refining), optionally written into a job file.
#include <spdlog/spdlog.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "client/args.h"
#include "client/bench_support.h"
#include "client/command.h"
#include "core/common/error.h"
#include "core/refine/bias_estimation.h"

namespace satmesh::cli {
namespace {

// The job file with every image's href absolute and its bias set to `bias[image path]`.
void WriteJobWithBiases(const std::string& job_path, const JobSpec& spec,
                        const std::vector<Eigen::Vector2d>& bias_per_job_image,
                        const std::string& out_path) {
  std::ifstream in(job_path);
  nlohmann::json job = nlohmann::json::parse(in);
  for (size_t i = 0; i < spec.images.size(); ++i) {
    job["images"][i]["href"] = spec.images[i].path;
    job["images"][i]["bias"] = {bias_per_job_image[i].x(), bias_per_job_image[i].y()};
  }
  job["initial"]["dsm"] = spec.initial_dsm;
  std::ofstream out(out_path);
  SATMESH_CHECK(out.good(), ErrorCode::kIo, "cannot write '" + out_path + "'");
  out << job.dump(2) << "\n";
}

int RunBias(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || !args.Has("job")) {
    std::printf(
        "usage: satmesh bias --job JOB.json [--pairs I-J,...] [--reference I] [--write-job OUT.json]\n"
        "                    [--set key=value ...]\n"
        "  Estimates per-image RPC bias shifts (col, row; full-resolution pixels) over the job's\n"
        "  initial surface: the reference image (most pairs, or --reference) stays fixed, the\n"
        "  others are aligned to the images solved before them. Pairs: the refinement's selection\n"
        "  (or --pairs, indices as the job runner keeps the images). Prints the estimate and the\n"
        "  total bias (job's + estimate); --write-job writes the job with the totals as bias.\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  const std::string job_path = args.Require("job");
  const JobSpec spec = ReadJobWithOverrides(job_path, args.GetAll("set"));
  const TileInput input = PrepareJobInput(spec);
  const int num_views = int(input.refine.views.size());
  BiasOptions options;
  options.refine = spec.refine;
  options.reference_view = args.GetInt("reference", -1);
  SATMESH_CHECK(options.reference_view < num_views, ErrorCode::kInvalidArgument,
                "--reference " + std::to_string(options.reference_view) + " out of range");
  const BiasEstimate estimate =
      args.Has("pairs")
          ? EstimateViewBiases(input.refine, ParsePairs(args.Require("pairs"), num_views), options)
          : EstimateRefineBiases(input.refine, options);
  std::printf("pairs:");
  for (const auto& [a, b] : estimate.pairs) std::printf(" %d-%d", a, b);
  std::printf("\n");

  std::vector<Eigen::Vector2d> totals;
  for (const auto& image : spec.images) totals.push_back(image.bias_col_row_px);
  std::printf("view  estimate col,row px   total col,row px   ZNCC before -> after  image\n");
  for (int v = 0; v < num_views; ++v) {
    const Eigen::Vector2d e = estimate.bias_col_row_px[v];
    const Eigen::Vector2d total = input.refine.views[v].rpc.bias() + e;
    for (size_t i = 0; i < spec.images.size(); ++i)
      if (spec.images[i].path == input.view_names[v]) totals[i] = total;
    const char* role = v == estimate.reference_view ? "reference"
                       : estimate.solved[v]         ? ""
                                                    : "(not paired)";
    std::printf("%4d  %+8.3f %+8.3f   %+8.3f %+8.3f   %.4f -> %.4f %s  %s\n", v, e.x(), e.y(),
                total.x(), total.y(), estimate.zncc_before[v], estimate.zncc_after[v], role,
                input.view_names[v].c_str());
  }
  if (args.Has("write-job")) {
    WriteJobWithBiases(job_path, spec, totals, args.Require("write-job"));
    std::printf("wrote %s\n", args.Require("write-job").c_str());
  }
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("bias", "per-image RPC bias shifts over the initial surface", RunBias);

}  // namespace satmesh::cli
