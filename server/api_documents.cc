#include "server/api_documents.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/common/error.h"
#include "proto/job_spec_json.h"

namespace satmesh::server {
namespace {

using nlohmann::json;

json Link(const std::string& href, const std::string& rel, const std::string& type,
          const std::string& title = "") {
  json link = {{"href", href}, {"rel", rel}, {"type", type}};
  if (!title.empty()) link["title"] = title;
  return link;
}

}  // namespace

json StatusInfo(const JobRecord& job) {
  int counts[5] = {0, 0, 0, 0, 0};
  double sum = 0;
  for (const auto& t : job.tiles) {
    ++counts[int(t.status)];
    sum += t.status == TileStatus::kDone ? 1.0 : t.status == TileStatus::kRunning ? t.progress : 0.0;
  }
  int progress = job.tiles.empty() ? 0 : int(100.0 * sum / double(job.tiles.size()));
  if (job.status == JobStatus::kSuccessful) progress = 100;
  else if (progress >= 100) progress = 99;  // assembling
  const std::string self = "/jobs/" + job.id;
  json links = json::array({Link(self, "self", "application/json", "this job"),
                            Link(self + "/tiles", "http://www.opengis.net/def/rel/ogc/1.0/tiles",
                                 "application/json", "per-tile status"),
                            Link(self + "/events", "monitor", "text/event-stream",
                                 "progress stream (server-sent events)")});
  if (job.status == JobStatus::kSuccessful)
    links.push_back(Link(self + "/results", "http://www.opengis.net/def/rel/ogc/1.0/results",
                         "application/json", "results"));
  json info = {{"processID", kProcessId}, {"type", "process"}, {"jobID", job.id},
               {"status", JobStatusName(job.status)}, {"message", job.message},
               {"created", job.created}, {"updated", job.updated}, {"progress", progress},
               {"tiles", {{"total", job.tiles.size()}, {"queued", counts[0]},
                          {"running", counts[1]}, {"done", counts[2]},
                          {"failed", counts[3]}, {"cancelled", counts[4]}}},
               {"links", links}};
  if (!job.started.empty()) info["started"] = job.started;
  if (!job.finished.empty()) info["finished"] = job.finished;
  return info;
}

json TileList(const JobRecord& job) {
  json tiles = json::array();
  for (const auto& t : job.tiles) {
    json tile = {{"x", t.key.x}, {"y", t.key.y}, {"status", TileStatusName(t.status)},
                 {"progress", t.status == TileStatus::kDone ? 1.0 : t.progress},
                 {"attempts", t.attempts}};
    if (t.status == TileStatus::kDone) {
      tile["duration_s"] = t.duration_s;
      tile["href"] = "/jobs/" + job.id + "/tiles/" + t.key.Name() + ".glb";
    }
    if (!t.message.empty()) tile["message"] = t.message;
    tiles.push_back(tile);
  }
  return {{"jobID", job.id}, {"tiles", tiles}};
}

json LiveTileset(const JobRecord& job) {
  Tileset ts;
  ts.region = {1e300, 1e300, -1e300, -1e300, 1e300, -1e300};
  for (const auto& t : job.tiles) {
    if (t.status != TileStatus::kDone || !t.result.is_object() || !t.result.contains("region") ||
        !t.result.contains("transform"))
      continue;
    TilesetTile tile;
    tile.name = t.key.Name();
    tile.uri = "tiles/" + t.key.Name() + ".glb";
    for (size_t i = 0; i < 6; ++i) tile.region[i] = t.result["region"].at(i).get<double>();
    for (size_t i = 0; i < 16; ++i) tile.transform[i] = t.result["transform"].at(i).get<double>();
    for (int k : {0, 1, 4}) ts.region[k] = std::min(ts.region[k], tile.region[k]);
    for (int k : {2, 3, 5}) ts.region[k] = std::max(ts.region[k], tile.region[k]);
    ts.tiles.push_back(tile);
  }
  if (ts.tiles.empty()) ts.region = {0, 0, 0, 0, 0, 0};
  // The root's geometric error: the region's larger side in metres (a viewer refines into
  // the leaves whenever the root is on screen).
  const double r = 6378137.0, lat = 0.5 * (ts.region[1] + ts.region[3]);
  ts.geometric_error = std::max((ts.region[2] - ts.region[0]) * r * std::cos(lat), (ts.region[3] - ts.region[1]) * r);
  json tileset = proto::TilesetToJson(ts);
  tileset["extras"] = {{"jobID", job.id}, {"status", JobStatusName(job.status)},
                       {"tiles_done", ts.tiles.size()}, {"tiles_total", job.tiles.size()}};
  return tileset;
}

json LandingPage() {
  return {{"title", "satmesh"},
          {"description", "Photometric multi-view refinement of 3D city meshes from satellite "
                          "images with RPC camera models (OGC API - Processes)"},
          {"links", json::array({Link("/", "self", "application/json"),
                                 Link("/api", "service-desc", "application/vnd.oai.openapi+json;version=3.0"),
                                 Link("/conformance", "http://www.opengis.net/def/rel/ogc/1.0/conformance", "application/json"),
                                 Link("/processes", "http://www.opengis.net/def/rel/ogc/1.0/processes", "application/json"),
                                 Link("/jobs", "http://www.opengis.net/def/rel/ogc/1.0/job-list", "application/json"),
                                 Link("/health", "service-status", "application/json"),
                                 Link("/metrics", "service-meta", "text/plain")})}};
}

json Conformance() {
  const std::string base = "http://www.opengis.net/spec/ogcapi-processes-1/1.0/conf/";
  return {{"conformsTo", json::array({base + "core", base + "json", base + "job-list",
                                      base + "dismiss", base + "oas30",
                                      "http://www.opengis.net/spec/ogcapi-common-1/1.0/conf/core"})}};
}

json ProcessSummary() {
  return {{"id", kProcessId}, {"title", "Refine a city mesh"}, {"version", "0.1.0"},
          {"description", "Moves the vertices of an initial surface (a DSM) so that image "
                          "pairs agree photometrically (ZNCC) under a thin-plate prior, "
                          "coarse to fine, tile by tile."},
          {"jobControlOptions", json::array({"async-execute", "dismiss"})},
          {"outputTransmission", json::array({"reference"})},
          {"links", json::array({Link(std::string("/processes/") + kProcessId, "self", "application/json"),
                                 Link(std::string("/processes/") + kProcessId + "/execution",
                                      "http://www.opengis.net/def/rel/ogc/1.0/execute",
                                      "application/json")})}};
}

json ProcessDescription(const json& job_schema) {
  json d = ProcessSummary();
  d["inputs"] = {{"job", {{"title", "job spec",},
                          {"description", "The job (execute request {\"inputs\": {\"job\": JOB}}; "
                                          "{\"inputs\": JOB} and JOB as the body are accepted too); "
                                          "hrefs are paths under the server's data roots (relative "
                                          "to the first) or allowed GDAL virtual paths."},
                          {"schema", job_schema}}}};
  d["outputs"] = {{"tileset", {{"title", "3D Tiles 1.1 tileset.json with one .glb per tile"},
                               {"schema", {{"type", "string"}, {"contentMediaType", "application/json"}}}}},
                  {"metrics", {{"title", "refinement metrics"}, {"schema", {{"type", "object"}}}}},
                  {"mesh", {{"title", "refined mesh (PLY)"},
                            {"schema", {{"type", "string"}, {"contentMediaType", "application/octet-stream"}}}}},
                  {"dsm", {{"title", "DSM of the refined mesh (GeoTIFF)"},
                           {"schema", {{"type", "string"}, {"contentMediaType", "image/tiff"}}}}}};
  return d;
}

std::string PrometheusText(const SchedulerStats& s) {
  std::ostringstream o;
  o << "# HELP satmesh_queue_depth Tiles waiting for a worker.\n"
    << "# TYPE satmesh_queue_depth gauge\nsatmesh_queue_depth " << s.tiles_queued << "\n"
    << "# HELP satmesh_tiles_running Tiles being refined now.\n"
    << "# TYPE satmesh_tiles_running gauge\nsatmesh_tiles_running " << s.tiles_running << "\n"
    << "# HELP satmesh_tiles_done_total Tiles finished since the server started.\n"
    << "# TYPE satmesh_tiles_done_total counter\nsatmesh_tiles_done_total " << s.tiles_done << "\n"
    << "# HELP satmesh_tiles_failed_total Tiles failed since the server started.\n"
    << "# TYPE satmesh_tiles_failed_total counter\nsatmesh_tiles_failed_total " << s.tiles_failed << "\n"
    << "# HELP satmesh_jobs Jobs in the store by status.\n# TYPE satmesh_jobs gauge\n";
  for (const char* status : {"accepted", "running", "successful", "failed", "dismissed"}) {
    const auto it = s.jobs_by_status.find(status);
    o << "satmesh_jobs{status=\"" << status << "\"} " << (it == s.jobs_by_status.end() ? 0 : it->second) << "\n";
  }
  o << "# HELP satmesh_tile_duration_seconds Wall time of finished tiles.\n"
    << "# TYPE satmesh_tile_duration_seconds histogram\n";
  for (size_t b = 0; b < s.duration_counts.size(); ++b) {
    o << "satmesh_tile_duration_seconds_bucket{le=\"";
    if (b < s.duration_buckets_s.size()) o << s.duration_buckets_s[b];
    else o << "+Inf";
    o << "\"} " << s.duration_counts[b] << "\n";
  }
  o << "satmesh_tile_duration_seconds_sum " << s.duration_sum_s << "\n"
    << "satmesh_tile_duration_seconds_count " << s.tiles_done << "\n";
  if (s.workers_seen >= 0)
    o << "# HELP satmesh_workers_seen Queue workers seen in the last minute.\n"
      << "# TYPE satmesh_workers_seen gauge\nsatmesh_workers_seen " << s.workers_seen << "\n";
  return o.str();
}

json ReadJsonFile(const std::string& path) {
  std::ifstream in(path);
  SATMESH_CHECK(in.good(), ErrorCode::kNotFound, "cannot open '" + path + "'");
  try {
    return json::parse(in);
  } catch (const json::parse_error& e) {
    ThrowError(ErrorCode::kInvalidInput, "'" + path + "': " + e.what());
  }
}

}  // namespace satmesh::server
