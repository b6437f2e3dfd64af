#include "server/real_executor.h"

#include <Eigen/Core>
#include <spdlog/spdlog.h>
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "core/common/error.h"
#include "core/image/image_io.h"
#include "core/mesh/mesh_io.h"
#include "core/tiling/input_check.h"
#include "core/tiling/job.h"
#include "core/tiling/memory_budget.h"
#include "proto/job_pictures.h"
#include "proto/job_spec_json.h"
#include "server/api_documents.h"

namespace satmesh::server {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

RasterInfo InfoFor(const std::string& path, const std::string& field) {
  try {
    return ReadRasterInfo(path);
  } catch (const Error& e) {
    ThrowError(ErrorCode::kInvalidArgument, field + ": " + e.what());
  }
}

// glTF/3D Tiles box: centre then three half-axis vectors.
json BoundingBox(const TriangleMesh& mesh) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(0), hi = lo;
  if (!mesh.vertices.empty()) lo = hi = mesh.vertices.front();
  for (const auto& v : mesh.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Vector3f c = (lo + hi) / 2, h = (hi - lo) / 2;
  return json::array({c.x(), c.y(), c.z(), h.x(), 0, 0, 0, h.y(), 0, 0, 0, h.z()});
}

// The job's biases (core/tiling/job.h, step 1b), once per job for every process that runs
// its tiles: the first tile to get here estimates them under an exclusive lock on
// job_dir/job_biases.lock and writes job_dir/job_biases.json; the others wait for the lock
// (cancellable) and read the file.
JobBiases JobBiasesFor(const JobSpec& spec, const JobPlan& plan, const std::string& job_dir,
                       const Progress& progress) {
  if (plan.tiles.size() <= 1 || !spec.refine.estimate_bias) return {};
  const fs::path path = fs::path(job_dir) / "job_biases.json";
  fs::create_directories(job_dir);
  const std::string lock_path = (fs::path(job_dir) / "job_biases.lock").string();
  const int fd = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) ThrowIoError("cannot open '" + lock_path + "'", errno);
  struct Unlock {
    int fd;
    ~Unlock() { ::flock(fd, LOCK_UN), ::close(fd); }
  } unlock{fd};
  while (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    progress.ThrowIfCancelled();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (fs::exists(path)) return proto::JobBiasesFromJson(ReadJsonFile(path.string()));
  const JobBiases biases = EstimateJobBiasesOnce(spec, plan, progress);
  WriteFileAtomic(path.string(), proto::JobBiasesToJson(biases).dump());
  return biases;
}

double UnixSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

bool TileRecordFailed(const json& record, std::string* code, std::string* message) {
  if (!record.is_object() || record.value("status", "") != "failed") return false;
  const json error = record.value("error", json::object());
  *code = error.is_object() ? error.value("code", "internal") : "internal";
  *message = error.is_object() ? error.value("message", "") : "";
  return true;
}

json FailedTileRecord(const TileKey& tile, const std::string& code, const std::string& message) {
  return {{"name", tile.Name()}, {"x", tile.x}, {"y", tile.y}, {"status", "failed"},
          {"error", {{"code", code}, {"message", message}}}};
}

void WriteFileAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.close();
    if (out.fail()) {
      const int error = errno;  // the failed write's (ENOSPC: the job waits for space)
      std::error_code ignored;
      fs::remove(tmp, ignored);
      ThrowIoError("cannot write '" + tmp + "'", error);
    }
  }
  fs::rename(tmp, path);
}

void WriteTileset(const std::string& job_dir, const std::vector<TileKey>& tiles) {
  json children = json::array();
  json root_box;
  for (const TileKey& key : tiles) {
    const std::string uri = "tiles/" + key.Name() + ".glb";
    const json box = BoundingBox(ReadMesh((fs::path(job_dir) / uri).string()));
    if (root_box.is_null()) root_box = box;
    children.push_back({{"boundingVolume", {{"box", box}}}, {"geometricError", 0},
                        {"content", {{"uri", uri}}}});
  }
  json root = {{"boundingVolume", {{"box", root_box.is_null() ? BoundingBox({}) : root_box}}},
               {"geometricError", 0}, {"refine", "ADD"}};
  if (children.size() == 1) root["content"] = children[0]["content"];
  else root["children"] = children;
  const json tileset = {{"asset", {{"version", "1.1"}, {"generator", "satmesh"}}},
                        {"geometricError", 0}, {"root", root}};
  WriteFileAtomic((fs::path(job_dir) / "tileset.json").string(), tileset.dump(2));
}

ExecutionPlan RealExecutor::Plan(const JobSpec& spec) {
  ExecutionPlan plan;
  for (size_t i = 0; i < spec.images.size(); ++i) {
    const RasterInfo info = InfoFor(spec.images[i].path, "images[" + std::to_string(i) + "].href");
    plan.pixels += int64_t(info.width) * info.height;
  }
  if (!spec.initial_dsm.empty()) InfoFor(spec.initial_dsm, "initial.dsm");
  const JobPlan job_plan = PlanJob(spec);
  CheckJobInputs(spec, job_plan);  // bad data refused at submission, named (422)
  for (const PlannedTile& tile : job_plan.tiles) plan.tiles.push_back({tile.x, tile.y});
  return plan;
}

json RealExecutor::RunTile(const JobSpec& spec, const TileKey& key, const std::string& job_dir,
                           const Progress& progress) {
  JobPlan plan = *plans_.Get(job_dir, [&] { return PlanJob(spec); });  // a copy (the budget)
  const int index = plan.IndexOf(key.x, key.y);
  SATMESH_CHECK(index >= 0, ErrorCode::kInternal, "tile " + key.Name() + " is not in the job's plan");
  if (tile_memory_budget_mb_ > 0) plan.memory_budget_mb = tile_memory_budget_mb_;
  const PlannedTile& tile = plan.tiles[size_t(index)];
  if (plan.memory_budget_mb > 0 && tile.memory.peak_mb > plan.memory_budget_mb) {
    // Refused before anything starts (the job's biases included); the record as core's
    // RunTile writes it for a tile over the budget.
    TileResult refused;
    refused.index = index;
    refused.name = tile.Name();
    refused.estimated_peak_mb = tile.memory.peak_mb;
    refused.error_code = ErrorCode::kInvalidArgument;
    refused.error = OverBudgetMessage("tile " + tile.Name(), tile.memory, plan.memory_budget_mb,
                                      tile_memory_budget_mb_ > 0 ? "this worker's --memory-budget"
                                                                 : "tiling.memory_budget_mb, --memory-budget");
    spdlog::warn("{}", refused.error);
    return proto::TileResultToJson(plan, refused);
  }
  const double started = UnixSeconds();
  const JobBiases biases = JobBiasesFor(spec, plan, job_dir, progress);
  TileResult result = satmesh::RunTile(TileSpec(spec, biases), plan, index, job_dir, progress);
  SetJobBiases(spec, biases, &result);
  json record = proto::TileResultToJson(plan, result);
  record["started_unix_s"] = started;  // the job's wall time at assembly: first start -> end
  return record;
}

json RealExecutor::Assemble(const JobSpec& spec, const std::vector<TileKey>& tiles,
                            const std::vector<json>& tile_results, const std::string& job_dir) {
  const std::shared_ptr<const JobPlan> shared = plans_.Get(job_dir, [&] { return PlanJob(spec); });
  const JobPlan& plan = *shared;
  std::vector<TileResult> results(plan.tiles.size());
  double first_start = UnixSeconds();
  for (const json& r : tile_results) {
    TileResult tile = proto::TileResultFromJson(plan, r);
    const int index = tile.index;
    results.at(size_t(index)) = std::move(tile);
    first_start = std::min(first_start, r.value("started_unix_s", first_start));
  }
  JobOutputs outputs = AssembleJob(plan, std::move(results), job_dir);
  const fs::path biases_path = fs::path(job_dir) / "job_biases.json";
  if (fs::exists(biases_path)) {
    const JobBiases biases = proto::JobBiasesFromJson(ReadJsonFile(biases_path.string()));
    outputs.job_bias_px = biases.bias_px;
    outputs.bias_tile = biases.tile;
    outputs.bias_s = biases.seconds;
  }
  // Tiles ran on the server's workers, possibly across restarts: the job's time is from
  // its first tile's start to now (queueing behind other jobs included).
  outputs.total_s = UnixSeconds() - first_start;
  outputs.tiles_s = outputs.total_s - outputs.assembly.assemble_s;
  json metrics = proto::JobMetricsToJson(outputs);
  WriteFileAtomic((fs::path(job_dir) / "tileset.json").string(),
                  proto::TilesetToJson(outputs.assembly.tileset).dump(2));
  WriteFileAtomic((fs::path(job_dir) / "metrics.json").string(), metrics.dump(2));
  proto::WriteJobPictures(metrics, job_dir);
  return metrics;
}

}  // namespace satmesh::server
