#pragma once
// Printing and JSON of evaluation reports (satmesh eval, satmesh demo). The core has no
// JSON; this is the adapter.
#include <nlohmann/json.hpp>
#include <string>

#include "core/eval/dsm_metrics.h"
#include "core/eval/mesh_metrics.h"
#include "core/eval/scene_eval.h"

namespace satmesh::cli {

nlohmann::json DsmMetricsToJson(const DsmMetrics& m);
nlohmann::json DsmEvaluationToJson(const DsmEvaluation& e);
nlohmann::json Mesh3dMetricsToJson(const Mesh3dMetrics& m);
nlohmann::json SurfaceEvaluationToJson(const SurfaceEvaluation& e);
// {"grid":{..}, "initial":{...}, "result":{...}, "ratio_result_over_initial":{...}}
nlohmann::json SceneEvaluationToJson(const SceneEvaluation& e);

// Table of initial vs result with the ratio result/initial, one metric per line.
std::string FormatSceneEvaluation(const SceneEvaluation& e);

}  // namespace satmesh::cli
