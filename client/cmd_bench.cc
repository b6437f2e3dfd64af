// satmesh bench: one refinement run (same path as `satmesh refine`) with per-level stage
// times, the time Embree alone needs for one full-resolution iteration's rays, peak
// memory and the machine's load.
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "client/args.h"
#include "client/bench_support.h"
#include "client/command.h"
#include "client/refine_runner.h"
#include "core/common/memory.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/tile_input.h"
#include "core/tiling/tile_plan.h"

namespace satmesh::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

// Per-iteration stage times: ray casting, the photometric pass, smoothing and the update
// run once an iteration (a level of 0 iterations: one pass that only measures).
StageTimes PerIteration(const LevelStats& level) {
  const double passes = std::max(1, level.iterations);
  return {level.times.hit_maps_s / passes, level.times.gradient_s / passes,
          level.times.smoothness_s / passes, level.times.update_s / passes,
          level.times.intersect_s / passes};
}
double Sum(const StageTimes& t) { return t.hit_maps_s + t.gradient_s + t.smoothness_s + t.update_s; }

nlohmann::json MachineJson(const MachineInfo& m) {
  return {{"cpu_model", m.cpu_model}, {"num_cpus", m.num_cpus}, {"mem_total_gib", m.mem_total_gib},
          {"load_avg", {m.load_1m, m.load_5m, m.load_15m}}};
}

// The job to run: --job, --scene DIR/job.json, or a generated preset scene (reused when
// its job.json exists).
std::string ResolveJob(const Args& args, const std::string& out, nlohmann::json* report) {
  if (args.Has("job")) return args.Require("job");
  if (args.Has("scene")) return (fs::path(args.Require("scene")) / "job.json").string();
  const std::string preset = args.GetOr("preset", "small");
  const int seed = args.GetInt("seed", 1);
  const fs::path scene = fs::path(out) / ("scene-" + preset + "-" + std::to_string(seed));
  const fs::path job = scene / "job.json";
  (*report)["scene"] = {{"preset", preset}, {"seed", seed}, {"dir", scene.string()}};
  if (fs::exists(job)) {
    std::printf("scene: reusing %s\n", scene.string().c_str());
    return job.string();
  }
  std::printf("scene: generating preset '%s' seed %d -> %s\n", preset.c_str(), seed, scene.string().c_str());
  const auto t0 = Clock::now();
  const auto result = synth::GenerateScene(scene.string(), synth::SynthPreset(preset, uint32_t(seed)));
  (*report)["scene"]["generate_s"] = Seconds(t0);
  (*report)["scene"]["num_views"] = result.views.size();
  std::printf("scene: %zu views, %d buildings, generated in %.1f s\n", result.views.size(),
              result.num_buildings, Seconds(t0));
  return job.string();
}

void PrintLevels(const RefineResult& refine) {
  std::printf("\n%5s %5s %9s %9s %6s %15s | per iteration [s]: %8s %8s %8s %8s %8s | %9s %8s"
              " | initial surface\n",
              "level", "iters", "vertices", "faces", "GSD_m", "mean ZNCC", "hit_maps", "gradient",
              "smooth", "update", "total", "intersect", "level_s");
  for (const auto& level : refine.levels) {
    const StageTimes t = PerIteration(level);
    // "0c": level 0 run again on its creases subdivided (RefineOptions::crease_pass)
    const std::string name = std::to_string(level.level) + (level.crease_pass ? "c" : "");
    std::printf("%5s %5d %9d %9d %6.2f %7.4f->%7.4f | %18s %8.3f %8.3f %8.3f %8.3f %8.3f | %9.3f %8.1f",
                name.c_str(), level.iterations, level.num_vertices, level.num_faces, level.gsd_m,
                level.mean_zncc.front(), level.mean_zncc.back(), "", t.hit_maps_s, t.gradient_s,
                t.smoothness_s, t.update_s, Sum(t), t.intersect_s, level.level_s);
    if (std::isnan(level.initial_zncc)) std::printf(" |\n");
    else std::printf(" | ZNCC %.4f, %s (%.1f s)\n", level.initial_zncc,
                     level.restarted ? "restarted from it" : "not used", level.initial_check_s);
  }
}

// The whole job's wall time by stage, for any job (one tile or many). Tile stages are
// summed over tiles: with several workers they add up to more than the wall time.
std::vector<std::pair<std::string, double>> JobStages(const JobOutputs& o) {
  std::vector<std::pair<std::string, double>> stages;
  double prepare = 0, bias = o.bias_s, setup = 0, write = 0;
  std::map<int, double> levels;
  for (const TileResult& t : o.tiles) {
    prepare += t.prepare_s;
    bias += t.bias_s;
    write += t.write_s;
    double levels_s = 0;
    for (const LevelStats& l : t.refine.levels) levels[l.level] += l.level_s, levels_s += l.level_s;
    setup += std::max(0.0, t.refine_s - t.bias_s - levels_s);
  }
  stages.push_back({"plan (DSM header, memory estimates)", o.plan_s});
  stages.push_back({"read image windows, initial mesh", prepare});
  stages.push_back({o.bias_tile.empty() ? "bias estimation (per tile)"
                                        : "bias estimation (once, tile " + o.bias_tile + ")",
                    bias});
  stages.push_back({"pyramids, pairs, coarse remesh", setup});
  for (auto it = levels.rbegin(); it != levels.rend(); ++it)
    stages.push_back({"level " + std::to_string(it->first), it->second});
  stages.push_back({"write tiles (dsm, ply, glb)", write});
  stages.push_back({"assemble (mesh.ply, dsm.tif, seams)", o.assembly.assemble_s});
  return stages;
}

void PrintJobStages(const JobOutputs& o) {
  std::printf("\nwhole job: %zu tile(s), %d worker(s)\n%-44s %9s %7s\n", o.tiles.size(), o.workers,
              "stage", "wall s", "share");
  for (const auto& [name, s] : JobStages(o))
    std::printf("%-44s %9.1f %6.1f%%\n", name.c_str(), s, 100 * s / std::max(1e-9, o.total_s));
  double estimated = 0;
  for (const TileResult& t : o.tiles) estimated = std::max(estimated, t.estimated_peak_mb);
  std::printf("%-44s %9.1f\npeak RSS %.0f MB (largest tile's estimate %.0f MB)\n", "total",
              o.total_s, o.peak_rss_mb, estimated);
}

int RunBench(const std::vector<std::string>& argv) {
  const Args args(argv, {"help"});
  if (args.Has("help") || !args.positionals().empty()) {
    std::printf(
        "usage: satmesh bench [--preset small|default|large --seed N | --scene DIR | --job JOB.json]\n"
        "                     [--out DIR] [--set key=value ...] [--repeats N] [--json OUT]\n"
        "  Refines (as `satmesh refine`) and reports per level the stage times per iteration, the\n"
        "  time Embree alone needs for the rays of one full-resolution iteration, peak memory.\n"
        "  Preset scenes are generated into DIR/scene-<preset>-<seed> (default DIR satmesh-bench)\n"
        "  and reused when present; results go to DIR/result.\n");
    return args.Has("help") ? kExitOk : kExitUsage;
  }
  const auto start = Clock::now();
  const std::string out = args.GetOr("out", "satmesh-bench");
  const auto overrides = args.GetAll("set");
  nlohmann::json report;
  const MachineInfo before = ReadMachineInfo();
  std::printf("machine: %s, %d logical CPUs, %.1f GiB; load average %.2f %.2f %.2f\n",
              before.cpu_model.c_str(), before.num_cpus, before.mem_total_gib, before.load_1m,
              before.load_5m, before.load_15m);
  report["machine_before"] = MachineJson(before);

  const std::string job = ResolveJob(args, out, &report);
  report["job"] = job;
  report["overrides"] = overrides;
  const auto refine_start = Clock::now();
  const double cpu_before_run = CpuSeconds();
  const JobOutputs outputs = RunJobFile(job, (fs::path(out) / "result").string(), overrides);
  const double run_s = Seconds(refine_start), run_cpu_s = CpuSeconds() - cpu_before_run;
  const RefineResult& refine = outputs.refine;
  PrintJobStages(outputs);
  nlohmann::json stages = nlohmann::json::array();
  for (const auto& [name, seconds] : JobStages(outputs)) stages.push_back({{"stage", name}, {"s", seconds}});
  report["stages"] = stages;
  report["total_s"] = outputs.total_s;
  report["peak_rss_mib"] = PeakRssMb();
  if (refine.levels.empty()) {  // a tiled job: no one tile's levels to time Embree against
    std::printf("(a tiled job: per-level iteration times and Embree alone are reported for "
                "one-tile jobs; run one tile with --set aoi=... for them)\n");
    if (args.Has("json")) std::ofstream(args.Require("json")) << report.dump(2) << "\n";
    return kExitOk;
  }
  PrintLevels(refine);

  // Embree alone on the final mesh with the rays of one level-0 iteration.
  const JobSpec spec = ReadJobWithOverrides(job, overrides);
  // The rays of the run's own windows: the one tile's when the job is one tile (an AOI).
  const JobPlan plan = PlanJob(spec);
  const TileInput input =
      plan.tiles.size() == 1 ? PrepareTileInput(spec, plan, 0) : PrepareJobInput(spec);
  std::set<int> used;
  for (const auto& [i, j] : refine.pairs) used.insert(i), used.insert(j);
  std::printf("pairs (%zu of %d candidates):", refine.pair_details.size(), refine.candidate_pairs);
  for (const StereoPair& p : refine.pair_details)
    std::printf(" %d-%d %.1f deg score %.2f;", p.i, p.j, p.angle_deg, p.score);
  std::printf("\n");
  std::printf("coarse start: %s\n", refine.grid_start > 0 ? "the DSM's grid" : "the remesh");
  const RaycastTiming ray = TimeRaycast(input.refine, refine.mesh, {used.begin(), used.end()},
                                        /*level=*/0, spec.refine.virtual_camera_grid_px,
                                        args.GetInt("repeats", 3));
  const LevelStats& finest = refine.levels.back();
  const double iteration_s = Sum(PerIteration(finest));
  const double ratio = iteration_s / std::max(1e-12, ray.intersect_s);
  std::printf("\nEmbree alone, level %d: %ld rays (%zu views), hit %.1f%%: BVH build %.3f s, "
              "Intersect %.3f s, CastHitMap %.3f s (best of %d)\n",
              finest.level, ray.num_rays, used.size(), 100 * ray.hit_fraction, ray.build_s,
              ray.intersect_s, ray.hit_map_s, args.GetInt("repeats", 3));
  std::printf("Rasterized hit maps of the same views: %.3f s (best of %d), same face as Embree "
              "at %.3f%% of the pixels\n",
              ray.raster_s, args.GetInt("repeats", 3), 100 * ray.raster_agreement);
  std::printf("level-%d iteration %.3f s = %.2fx Embree alone (issue target: <= 2x)\n",
              finest.level, iteration_s, ratio);
  // The same-moment comparison: Embree's Intersect timed inside each iteration (when the
  // run ray-casts its hit maps, rasterize_hit_maps=false).
  const double in_run_intersect_s = PerIteration(finest).intersect_s;
  const double in_run_ratio = in_run_intersect_s > 0 ? iteration_s / in_run_intersect_s : 0;
  if (in_run_intersect_s > 0)
    std::printf("level-%d iteration = %.2fx the Intersect inside the same iterations (%.3f s)\n",
                finest.level, in_run_ratio, in_run_intersect_s);

  const MachineInfo after = ReadMachineInfo();
  const double total_s = Seconds(start);
  std::printf("pairs %zu; prepare %.1f s, refine %.1f s, write %.1f s, run %.1f s (CPU %.1f s = "
              "%.2f cores); total %.1f s; peak RSS %.0f MiB; load average %.2f %.2f %.2f\n",
              refine.pairs.size(), outputs.prepare_s, refine.total_s, outputs.write_s, run_s,
              run_cpu_s, run_cpu_s / std::max(1e-9, run_s), total_s, PeakRssMb(), after.load_1m,
              after.load_5m, after.load_15m);

  if (args.Has("json")) {
    nlohmann::json levels = nlohmann::json::array();
    for (const auto& level : refine.levels) {
      const StageTimes t = PerIteration(level);
      levels.push_back({{"level", level.level}, {"iterations", level.iterations},
                        {"pair_directions", level.pair_directions},
                        {"vertices", level.num_vertices}, {"faces", level.num_faces},
                        {"gsd_m", level.gsd_m}, {"mean_zncc", level.mean_zncc},
                        {"per_iteration_s", {{"hit_maps", t.hit_maps_s}, {"gradient", t.gradient_s},
                                             {"smoothness", t.smoothness_s}, {"update", t.update_s},
                                             {"total", Sum(t)}, {"intersect", t.intersect_s}}},
                        {"initial_zncc", level.initial_zncc},
                        {"restarted_from_initial", level.restarted},
                        {"crease_pass", level.crease_pass},
                        {"initial_check_s", level.initial_check_s},
                        {"level_s", level.level_s}});
    }
    report["levels"] = levels;
    report["num_pairs"] = refine.pairs.size();
    nlohmann::json pairs = nlohmann::json::array();
    for (const StereoPair& p : refine.pair_details)
      pairs.push_back({{"views", {p.i, p.j}}, {"angle_deg", p.angle_deg}, {"score", p.score}});
    report["pairs"] = pairs;
    report["embree_alone"] = {{"level", finest.level}, {"num_rays", ray.num_rays},
                              {"num_views", used.size()}, {"hit_fraction", ray.hit_fraction},
                              {"build_s", ray.build_s}, {"intersect_s", ray.intersect_s},
                              {"cast_hit_map_s", ray.hit_map_s}, {"raster_s", ray.raster_s},
                              {"raster_agreement", ray.raster_agreement}, {"iteration_s", iteration_s},
                              {"iteration_over_intersect", ratio},
                              {"iteration_over_in_run_intersect",
                               in_run_intersect_s > 0 ? nlohmann::json(in_run_ratio) : nlohmann::json()}};
    report["prepare_s"] = outputs.prepare_s;
    report["refine_s"] = refine.total_s;
    report["write_s"] = outputs.write_s;
    report["run_cpu_s"] = run_cpu_s;
    report["run_s"] = run_s;
    report["total_s"] = total_s;
    report["peak_rss_mib"] = PeakRssMb();
    report["machine_after"] = MachineJson(after);
    std::ofstream(args.Require("json")) << report.dump(2) << "\n";
    std::printf("wrote %s\n", args.Require("json").c_str());
  }
  return kExitOk;
}

}  // namespace

SATMESH_REGISTER_COMMAND("bench", "benchmark one refinement (stage times, Embree, memory)", RunBench);

}  // namespace satmesh::cli
