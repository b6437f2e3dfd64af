#include "server/real_executor.h"

#include <Eigen/Core>
#include <filesystem>
#include <fstream>

#include "core/common/error.h"
#include "core/image/image_io.h"
#include "core/mesh/mesh_io.h"
#include "core/tiling/job.h"
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

template <size_t N>
std::array<double, N> ArrayFrom(const json& j) {
  std::array<double, N> a{};
  for (size_t i = 0; i < N && i < j.size(); ++i) a[i] = j[i].get<double>();
  return a;
}

// The persisted tile record back into what AssembleOutputs reads.
TileResult TileFromJson(const JobPlan& plan, const json& j) {
  TileResult t;
  t.index = plan.IndexOf(j.at("x"), j.at("y"));
  SATMESH_CHECK(t.index >= 0, ErrorCode::kInternal, "tile " + j.value("name", std::string("?")) + " is not in the plan");
  t.name = j.value("name", plan.tiles[t.index].Name());
  t.ok = true;
  t.region = ArrayFrom<6>(j.at("region"));
  t.transform = ArrayFrom<16>(j.at("transform"));
  t.core_vertices = j.value("vertices", size_t{0});
  t.core_faces = j.value("faces", size_t{0});
  t.view_names = j.value("views", std::vector<std::string>{});
  t.image_mb = j.value("image_mb", 0.0);
  if (j.contains("time_s")) {
    t.prepare_s = j["time_s"].value("prepare", 0.0);
    t.refine_s = j["time_s"].value("refine", 0.0);
    t.write_s = j["time_s"].value("write", 0.0);
  }
  return t;
}

}  // namespace

void WriteFileAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    SATMESH_CHECK(out.good(), ErrorCode::kIo, "cannot write '" + tmp + "'");
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
  InfoFor(spec.initial_dsm, "initial.dsm");
  for (const PlannedTile& tile : PlanJob(spec).tiles) plan.tiles.push_back({tile.x, tile.y});
  return plan;
}

json RealExecutor::RunTile(const JobSpec& spec, const TileKey& key, const std::string& job_dir,
                           const Progress& progress) {
  const JobPlan plan = PlanJob(spec);
  const int index = plan.IndexOf(key.x, key.y);
  SATMESH_CHECK(index >= 0, ErrorCode::kInternal, "tile " + key.Name() + " is not in the job's plan");
  const TileResult result = satmesh::RunTile(spec, plan, index, job_dir, progress);
  if (!result.ok) ThrowError(result.error_code, result.error);
  json record = proto::TileResultToJson(plan, result);
  record["region"] = result.region;
  record["transform"] = result.transform;
  return record;
}

json RealExecutor::Assemble(const JobSpec& spec, const std::vector<TileKey>& tiles,
                            const std::vector<json>& tile_results, const std::string& job_dir) {
  JobOutputs outputs;
  outputs.plan = PlanJob(spec);
  for (const json& r : tile_results) outputs.tiles.push_back(TileFromJson(outputs.plan, r));
  outputs.assembly = AssembleOutputs(outputs.plan, outputs.tiles, job_dir);
  outputs.mesh_path = outputs.assembly.mesh_path;
  outputs.dsm_path = outputs.assembly.dsm_path;
  if (outputs.tiles.size() == 1) outputs.view_names = outputs.tiles[0].view_names;
  json metrics = proto::JobMetricsToJson(outputs);
  json full_tiles = json::array();  // as recorded when each tile ran (with its levels)
  for (json r : tile_results) {
    r.erase("region");
    r.erase("transform");
    full_tiles.push_back(r);
  }
  metrics["tiles"] = full_tiles;
  WriteFileAtomic((fs::path(job_dir) / "tileset.json").string(),
                  proto::TilesetToJson(outputs.assembly.tileset).dump(2));
  WriteFileAtomic((fs::path(job_dir) / "metrics.json").string(), metrics.dump(2));
  return metrics;
}

}  // namespace satmesh::server
