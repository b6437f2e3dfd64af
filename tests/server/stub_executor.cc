#include "tests/server/stub_executor.h"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "core/common/error.h"
#include "core/mesh/mesh_io.h"
#include "server/real_executor.h"

namespace satmesh::server::testing {
namespace fs = std::filesystem;

ExecutionPlan StubExecutor::Plan(const JobSpec& spec) {
  ExecutionPlan plan;
  last_memory_budget_mb_ = spec.tiling.memory_budget_mb;
  for (int y = 0; y < options_.tiles_y; ++y)
    for (int x = 0; x < options_.tiles_x; ++x) plan.tiles.push_back({x, y});
  plan.pixels = int64_t(spec.images.size()) * 1000;
  return plan;
}

nlohmann::json StubExecutor::RunTile(const JobSpec&, const TileKey& tile, const std::string& job_dir,
                                     const Progress& progress) {
  const int now = ++running_;
  int seen = max_concurrent_.load();
  while (now > seen && !max_concurrent_.compare_exchange_weak(seen, now)) {
  }
  struct Leave {
    std::atomic<int>* n;
    ~Leave() { --*n; }
  } leave{&running_};
  const int steps = std::max(1, options_.tile_ms / 10);
  for (int i = 0; i < steps; ++i) {
    progress.ThrowIfCancelled();
    std::this_thread::sleep_for(std::chrono::milliseconds(options_.tile_ms / steps));
    progress.Report(double(i + 1) / steps, "stub");
  }
  if (tile.Name() == options_.fail_tile)  // a failed tile is a record (executor.h)
    return FailedTileRecord(tile, ErrorCodeName(ErrorCode::kInvalidInput), "stub: tile " + tile.Name() + " fails");
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, float(tile.x + tile.y)}};
  mesh.faces = {{0, 1, 2}};
  fs::create_directories(fs::path(job_dir) / "tiles");
  const fs::path tmp = fs::path(job_dir) / "tiles" / (".partial." + tile.Name() + ".glb");
  WriteMesh(tmp.string(), mesh);
  fs::rename(tmp, fs::path(job_dir) / "tiles" / (tile.Name() + ".glb"));
  const std::string line = tile.Name() + "\n";
  const int fd = ::open((fs::path(job_dir) / "completions.log").c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd >= 0) {
    [[maybe_unused]] const ssize_t n = ::write(fd, line.data(), line.size());
    ::close(fd);
  }
  return {{"tile", tile.Name()}, {"faces", 1}};
}

nlohmann::json StubExecutor::Assemble(const JobSpec&, const std::vector<TileKey>& tiles,
                                      const std::vector<nlohmann::json>& tile_results,
                                      const std::string& job_dir) {
  std::vector<TileKey> done;
  int faces = 0;
  for (size_t i = 0; i < tiles.size(); ++i) {
    std::string code, message;
    if (TileRecordFailed(tile_results[i], &code, &message)) continue;
    done.push_back(tiles[i]);
    faces += tile_results[i].value("faces", 0);
  }
  WriteTileset(job_dir, done);
  const nlohmann::json metrics = {{"engine", "stub"}, {"tiles", done.size()}, {"faces", faces}};
  WriteFileAtomic((fs::path(job_dir) / "metrics.json").string(), metrics.dump());
  return metrics;
}

nlohmann::json MakeStubJob(const std::string& root) {
  fs::create_directories(root);
  for (const char* name : {"a.tif", "b.tif", "dsm.tif"}) std::ofstream(fs::path(root) / name) << "stub";
  return {{"images", {{{"href", "a.tif"}}, {{"href", "b.tif"}}}},
          {"initial", {{"dsm", "dsm.tif"}}},
          {"options", {{"levels", 1}}}};
}

}  // namespace satmesh::server::testing
