#pragma once
// The JSON documents the API serves (statusInfo, landing page, process description,
// Prometheus metrics text); pure functions of the scheduler's records.
#include <nlohmann/json.hpp>
#include <string>

#include "server/scheduler.h"
#include "server/store.h"

namespace satmesh::server {

constexpr const char* kProcessId = "refine-mesh";

// OGC statusInfo plus a `tiles` summary (total, queued, running, done, failed, cancelled).
nlohmann::json StatusInfo(const JobRecord& job);
// Per-tile list: key, status, progress, duration, href of the glb when done.
nlohmann::json TileList(const JobRecord& job);
// 3D Tiles 1.1 tileset of the job's tiles finished so far (from their records' region and
// transform), content uris relative to /jobs/{id}/; extras: status, tiles_done/total.
nlohmann::json LiveTileset(const JobRecord& job);
nlohmann::json LandingPage();
nlohmann::json Conformance();
nlohmann::json ProcessSummary();
// The process description with the job schema (proto/job.schema.json) as its input.
nlohmann::json ProcessDescription(const nlohmann::json& job_schema);
// Prometheus text exposition format (version 0.0.4).
std::string PrometheusText(const SchedulerStats& stats);
// Reads a JSON file; throws Error{kNotFound}/{kInvalidInput} naming it.
nlohmann::json ReadJsonFile(const std::string& path);

}  // namespace satmesh::server
