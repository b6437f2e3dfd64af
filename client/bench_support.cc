#include "client/bench_support.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <utility>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/dsm/fill_holes.h"
#include "core/mesh/mesh_io.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/hit_map_raster.h"
#include "core/refine/view_level.h"
#include "proto/job_spec_json.h"

namespace satmesh::cli {
namespace {

using Clock = std::chrono::steady_clock;
double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

}  // namespace

TileInput PrepareJobInput(const JobSpec& spec) {
  Dsm dsm = ReadDsm(spec.initial_dsm);
  const double coarse_cell = CoarseCellSize(spec.refine, std::abs(dsm.geo_transform[1]));
  return PrepareTileInput(spec, std::move(dsm), coarse_cell);
}

TriangleMesh LoadMeshInFrame(const std::string& path, const JobSpec& spec,
                             const std::string& default_crs, const LocalFrame& frame) {
  namespace fs = std::filesystem;
  const bool filled = path == "initial-filled";
  std::string file = path == "initial" || filled ? spec.initial_dsm : path;
  if (fs::is_directory(file)) file = (fs::path(file) / "mesh.ply").string();
  std::string ext = fs::path(file).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".tif" || ext == ".tiff") {
    Dsm dsm = ReadDsm(file);
    if (filled) FillDsmHoles(&dsm, spec.fill_holes_m);
    return MeshInFrame(MeshFromDsm(dsm), dsm.crs_wkt, frame);
  }
  const TriangleMesh mesh = ReadMesh(file);
  return MeshInFrame(mesh, mesh.crs.empty() ? default_crs : mesh.crs, frame);
}

std::vector<std::pair<int, int>> ParsePairs(const std::string& text, int num_views) {
  std::vector<std::pair<int, int>> pairs;
  std::stringstream items(text);
  std::string item;
  while (std::getline(items, item, ',')) {
    int a = -1, b = -1;
    char dash = 0, extra = 0;
    std::stringstream s(item);
    const bool ok = bool(s >> a >> dash >> b) && dash == '-' && !(s >> extra);
    SATMESH_CHECK(ok && a != b, ErrorCode::kInvalidArgument,
                  "--pairs: '" + item + "' is not of the form I-J with I != J");
    SATMESH_CHECK(a >= 0 && b >= 0 && a < num_views && b < num_views, ErrorCode::kInvalidArgument,
                  "--pairs: '" + item + "' names a view outside [0, " + std::to_string(num_views) + ")");
    pairs.emplace_back(a, b);
  }
  SATMESH_CHECK(!pairs.empty(), ErrorCode::kInvalidArgument, "--pairs: no pair in '" + text + "'");
  return pairs;
}

RaycastTiming TimeRaycast(const RefineInput& input, const TriangleMesh& mesh,
                          const std::vector<int>& views, int level, int grid_px, int repeats) {
  Eigen::Vector3d box_min, box_max;
  SurfaceBox(mesh, input.min_z, input.max_z, &box_min, &box_max);  // as MakeViewLevels
  std::vector<ViewLevel> levels;
  for (int v : views) {
    const ImageF& full = input.views[v].image;
    const int scale = 1 << level;
    ImageF size_only((full.width + scale - 1) / scale, (full.height + scale - 1) / scale);
    levels.push_back(MakeViewLevel(v, level, std::move(size_only), input.views[v].rpc, input.frame,
                                   box_min, box_max, grid_px));
  }
  RaycastTiming timing;
  auto t0 = Clock::now();
  const RayScene scene(mesh);
  timing.build_s = Seconds(t0);
  std::vector<std::vector<Ray>> rays;  // made before the clock starts
  for (const auto& v : levels) rays.push_back(PixelRays(v));
  std::vector<RayHit> hits;
  timing.intersect_s = timing.hit_map_s = 1e300;
  for (int r = 0; r < std::max(1, repeats); ++r) {
    t0 = Clock::now();
    for (const auto& view_rays : rays) {
      hits.resize(view_rays.size());
      scene.Intersect(view_rays.data(), hits.data(), view_rays.size());
    }
    timing.intersect_s = std::min(timing.intersect_s, Seconds(t0));
    t0 = Clock::now();
    for (auto& v : levels) CastHitMap(scene, &v);
    timing.hit_map_s = std::min(timing.hit_map_s, Seconds(t0));
  }
  long hit = 0;
  for (const auto& v : levels) {
    timing.num_rays += long(v.ray_directions.size());
    for (const auto& h : v.hit_map.hits) hit += h.hit();
  }
  // The rasterized hit maps of the same views, and how often they agree with Embree's.
  std::vector<std::vector<RayHit>> embree_hits;
  for (const auto& v : levels) embree_hits.push_back(v.hit_map.hits);
  HitMapScratch raster;
  timing.raster_s = 1e300;
  for (int r = 0; r < std::max(1, repeats); ++r) {
    t0 = Clock::now();
    RasterizeHitMaps(mesh, &levels, &raster);
    timing.raster_s = std::min(timing.raster_s, Seconds(t0));
  }
  long same = 0;
  for (size_t k = 0; k < levels.size(); ++k)
    for (size_t p = 0; p < embree_hits[k].size(); ++p)
      same += embree_hits[k][p].face == levels[k].hit_map.hits[p].face;
  timing.raster_agreement = timing.num_rays > 0 ? double(same) / timing.num_rays : 0;
  timing.hit_fraction = timing.num_rays > 0 ? double(hit) / timing.num_rays : 0;
  return timing;
}

MachineInfo ReadMachineInfo() {
  MachineInfo info;
  info.num_cpus = int(std::thread::hardware_concurrency());
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      info.cpu_model = line.substr(line.find(':') + 2);
      break;
    }
  }
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  double kib = 0;
  if (meminfo >> key >> kib && key == "MemTotal:") info.mem_total_gib = kib / (1024.0 * 1024.0);
  std::ifstream("/proc/loadavg") >> info.load_1m >> info.load_5m >> info.load_15m;
  return info;
}

double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

}  // namespace satmesh::cli
