#pragma once
// Measurement helpers shared by `satmesh bench` and `satmesh zncc`: rebuilding a job's
// refinement input the way the job runner does, bringing meshes into its local frame,
// timing Embree alone on one level's rays, and describing the machine.
#include <string>
#include <utility>
#include <vector>

#include "client/refine_runner.h"  // ReadJobWithOverrides
#include "core/tiling/job.h"
#include "core/tiling/tile_input.h"

namespace satmesh::cli {

// The refinement input RunJob builds for `spec` (same frame, windows and coarse cell).
TileInput PrepareJobInput(const JobSpec& spec);

// A mesh into `frame`: `path` is a mesh file (mesh.crs, or `default_crs` when the file
// has none), a directory holding mesh.ply (a refine result), a .tif DSM (triangulated at
// its full resolution), "initial" (the job's initial DSM at full resolution) or
// "initial-filled" (the same with its holes filled as the refinement fills them).
TriangleMesh LoadMeshInFrame(const std::string& path, const JobSpec& spec,
                             const std::string& default_crs, const LocalFrame& frame);

// "0-2,1-2" -> {(0,2), (1,2)}; throws Error{kInvalidArgument} naming a bad item or an
// index outside [0, num_views).
std::vector<std::pair<int, int>> ParsePairs(const std::string& text, int num_views);

// Embree alone on the rays one refinement iteration casts at `level`: one ray per pixel
// of every listed view's level image, against a RayScene of `mesh` (frame coordinates).
struct RaycastTiming {
  long num_rays = 0;
  double build_s = 0;        // RayScene construction (BVH build)
  double intersect_s = 0;    // RayScene::Intersect over all rays (best of the repeats)
  double hit_map_s = 0;      // CastHitMap for all views (Intersect + hit points; best)
  double raster_s = 0;       // RasterizeHitMap for all views (the same hit maps; best)
  double raster_agreement = 0;  // fraction of pixels where both give the same face (or miss)
  double hit_fraction = 0;   // fraction of rays that hit
};
RaycastTiming TimeRaycast(const RefineInput& input, const TriangleMesh& mesh,
                          const std::vector<int>& views, int level, int grid_px, int repeats);

// The machine: CPU model, logical cores, memory, load averages, peak RSS of this process.
struct MachineInfo {
  std::string cpu_model;
  int num_cpus = 0;
  double mem_total_gib = 0;
  double load_1m = 0, load_5m = 0, load_15m = 0;
};
MachineInfo ReadMachineInfo();
// User + system CPU seconds of this process so far (all threads): under a shared, loaded
// machine this is steadier than wall time.
double CpuSeconds();

}  // namespace satmesh::cli
