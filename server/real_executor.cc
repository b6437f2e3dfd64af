#include "server/real_executor.h"

#include <Eigen/Core>
#include <filesystem>
#include <fstream>

#include "core/common/error.h"
#include "core/image/image_io.h"
#include "core/mesh/mesh_io.h"
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
  plan.tiles = {TileKey{0, 0}};  // core RunJob refines the whole AOI as one tile
  return plan;
}

json RealExecutor::RunTile(const JobSpec& spec, const TileKey& tile, const std::string& job_dir,
                           const Progress& progress) {
  const fs::path work = fs::path(job_dir) / "work" / tile.Name();
  fs::create_directories(work);
  fs::create_directories(fs::path(job_dir) / "tiles");
  const JobOutputs outputs = RunJob(spec, work.string(), progress);
  WriteFileAtomic((work / "metrics.json").string(), proto::RefineMetricsToJson(outputs).dump(2));
  const fs::path glb = fs::path(job_dir) / "tiles" / (tile.Name() + ".glb");
  const fs::path tmp = fs::path(job_dir) / "tiles" / (".partial." + tile.Name() + ".glb");
  WriteMesh(tmp.string(), ReadMesh(outputs.mesh_path));
  fs::rename(tmp, glb);
  return {{"work", "work/" + tile.Name()}};
}

json RealExecutor::Assemble(const JobSpec& spec, const std::vector<TileKey>& tiles,
                            const std::vector<json>& tile_results, const std::string& job_dir) {
  SATMESH_CHECK(tiles.size() == 1, ErrorCode::kInternal, "the single-tile runner got several tiles");
  const fs::path dir(job_dir), work = dir / "work" / tiles[0].Name();
  json metrics = ReadJsonFile((work / "metrics.json").string());
  for (const char* file : {"mesh.ply", "dsm.tif"}) fs::copy_file(work / file, dir / file, fs::copy_options::overwrite_existing);
  metrics["outputs"]["tileset"] = "tileset.json";
  WriteTileset(job_dir, tiles);
  WriteFileAtomic((dir / "metrics.json").string(), metrics.dump(2));
  return metrics;
}

}  // namespace satmesh::server
