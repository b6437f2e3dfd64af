#pragma once
// The job spec's wire format (proto/job.schema.json) <-> core JobSpec, and the refine
// metrics as JSON. Shared by the CLI and the server; the core stays JSON-free.
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
// Applies "key=value" overrides to job["options"] (value parsed as JSON, else string).
void ApplyOptionOverride(nlohmann::json* job, const std::string& key_equals_value);

nlohmann::json RefineMetricsToJson(const JobOutputs& outputs);

}  // namespace satmesh::proto
