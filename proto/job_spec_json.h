#pragma once
// The job spec's wire format (proto/job.schema.json) <-> core JobSpec, and the job's
// outputs (metrics.json, tileset.json) as JSON. Shared by the CLI and the server; the core stays JSON-free.
#include <nlohmann/json.hpp>
#include <string>

#include "core/tiling/job.h"

namespace satmesh::proto {

// Validates against the schema's rules and throws Error{kInvalidArgument} with the JSON
// path of the offending field ("images[2].href: expected a string"). Relative hrefs are
// resolved against base_dir.
JobSpec JobSpecFromJson(const nlohmann::json& job, const std::string& base_dir);
// Reads and parses a job file; hrefs relative to its directory.
JobSpec ReadJobFile(const std::string& path);
// Applies a "key=value" override (value parsed as JSON, else a string): "levels=2" sets
// options.levels, "tiling.size_m=100" sets job["tiling"]["size_m"], and
// 'aoi={"bbox": [...]}' (or tiling=, outputs=, initial=) replaces that top-level object
// ('initial={"mesh": "runs/a/"}' refines a previous result).
// A key without a dot (or options.KEY) must be a refinement option (RefineOptionTable()).
void ApplyOptionOverride(nlohmann::json* job, const std::string& key_equals_value);

// The JSON Schema of each option of RefineOptionTable() / TilingOptionTable() (type,
// default, minimum/maximum or their exclusive forms, description): what job.schema.json's
// "options" / "tiling" "properties" hold (a test keeps the file and the process
// description to them).
nlohmann::json RefineOptionsSchema();
nlohmann::json TilingOptionsSchema();

// Outputs (core structs -> JSON). metrics.json: per tile and totals (+ the single-tile
// refinement stats at top level, as before tiling). tileset.json: 3D Tiles 1.1.
nlohmann::json TileResultToJson(const JobPlan& plan, const TileResult& tile);
// Back from TileResultToJson (what AssembleOutputs needs: status, region, transform,
// counts, times; not the per-level stats), so a restarted server can assemble tiles
// finished before. Throws Error{kInvalidArgument} for a tile name not in the plan.
TileResult TileResultFromJson(const JobPlan& plan, const nlohmann::json& tile);
nlohmann::json TilesetToJson(const Tileset& tileset);
// The job's biases (job.h, step 1b) and back: {"bias_px": [[col, row], ...] in the job's
// image order, "tile", "seconds"}; an empty "bias_px" means each tile estimates its own.
nlohmann::json JobBiasesToJson(const JobBiases& biases);
JobBiases JobBiasesFromJson(const nlohmann::json& biases);
nlohmann::json JobMetricsToJson(const JobOutputs& outputs);
nlohmann::json RefineMetricsToJson(const JobOutputs& outputs);  // = JobMetricsToJson
// Writes out_dir/tileset.json and out_dir/metrics.json (each atomically).
void WriteJobJson(const JobOutputs& outputs, const std::string& out_dir);

}  // namespace satmesh::proto
