#include "client/eval_report_format.h"

#include <fmt/format.h>

#include <cmath>
#include <functional>

namespace satmesh::cli {
namespace {

using nlohmann::json;

std::string ThresholdKey(double t) { return fmt::format("{:g}m", t); }

json ScoresToJson(const Mesh3dScores& s) {
  json j;
  j["num_result_samples"] = s.num_result_samples;
  j["num_truth_samples"] = s.num_truth_samples;
  for (size_t t = 0; t < s.thresholds_m.size(); ++t) {
    const std::string k = ThresholdKey(s.thresholds_m[t]);
    j["accuracy"][k] = s.accuracy[t];
    j["completeness"][k] = s.completeness[t];
    j["fscore"][k] = s.fscore[t];
  }
  return j;
}

// Ratio of every number in `result` to the same number in `initial` (null if 0 or absent).
json Ratios(const json& initial, const json& result) {
  if (result.is_object()) {
    json out = json::object();
    for (auto it = result.begin(); it != result.end(); ++it)
      if (initial.contains(it.key())) out[it.key()] = Ratios(initial[it.key()], it.value());
    return out;
  }
  if (result.is_number() && initial.is_number()) {
    const double a = initial.get<double>(), b = result.get<double>();
    return a != 0 ? json(b / a) : json(nullptr);
  }
  return nullptr;
}

struct Row {
  std::string label;
  std::function<double(const SurfaceEvaluation&)> get;
  bool percent = false;
};

void AddDsmRows(std::vector<Row>& rows, const std::string& where,
                std::function<const DsmMetrics&(const SurfaceEvaluation&)> pick) {
  auto add = [&](std::string name, std::function<double(const DsmMetrics&)> f, bool pct) {
    rows.push_back({where + " " + name, [pick, f](const SurfaceEvaluation& e) { return f(pick(e)); }, pct});
  };
  add("completeness <3m", [](const DsmMetrics& m) { return m.completeness; }, true);
  add("completeness <1m", [](const DsmMetrics& m) { return m.completeness_1m; }, true);
  add("completeness <0.5m", [](const DsmMetrics& m) { return m.completeness_05m; }, true);
  add("RMSE (|r|<3m) [m]", [](const DsmMetrics& m) { return m.rmse_m; }, false);
  add("NMAD [m]", [](const DsmMetrics& m) { return m.nmad_m; }, false);
  add("perc-68 [m]", [](const DsmMetrics& m) { return m.perc68_m; }, false);
  add("MAE [m]", [](const DsmMetrics& m) { return m.mae_m; }, false);
  add("median [m]", [](const DsmMetrics& m) { return m.median_m; }, false);
}

void Add3dRows(std::vector<Row>& rows, const std::string& where, const Mesh3dScores& shape,
               std::function<const Mesh3dScores&(const SurfaceEvaluation&)> pick) {
  for (size_t t = 0; t < shape.thresholds_m.size(); ++t) {
    const std::string th = fmt::format("@{:g}m", shape.thresholds_m[t]);
    rows.push_back({where + " accuracy " + th,
                    [pick, t](const SurfaceEvaluation& e) { return pick(e).accuracy[t]; }, true});
    rows.push_back({where + " completeness " + th,
                    [pick, t](const SurfaceEvaluation& e) { return pick(e).completeness[t]; }, true});
    rows.push_back({where + " F-score " + th,
                    [pick, t](const SurfaceEvaluation& e) { return pick(e).fscore[t]; }, true});
  }
}

}  // namespace

json DsmMetricsToJson(const DsmMetrics& m) {
  return {{"num_cells", m.num_cells},         {"num_valid", m.num_valid},
          {"completeness_3m", m.completeness}, {"completeness_1m", m.completeness_1m},
          {"completeness_0.5m", m.completeness_05m}, {"rmse_m", m.rmse_m},
          {"nmad_m", m.nmad_m},                {"perc68_m", m.perc68_m},
          {"mae_m", m.mae_m},                  {"median_m", m.median_m}};
}

json DsmEvaluationToJson(const DsmEvaluation& e) {
  return {{"roof_mask", {{"raw", DsmMetricsToJson(e.mask_raw)},
                         {"aligned", DsmMetricsToJson(e.mask_aligned)}}},
          {"all_cells", {{"raw", DsmMetricsToJson(e.all_raw)},
                         {"aligned", DsmMetricsToJson(e.all_aligned)}}},
          {"alignment", {{"dx_m", e.alignment.dx_m}, {"dy_m", e.alignment.dy_m},
                         {"dz_m", e.alignment.dz_m}}}};
}

json Mesh3dMetricsToJson(const Mesh3dMetrics& m) {
  json j = {{"all", ScoresToJson(m.all)}, {"facade", ScoresToJson(m.facade)},
            {"under_overhang", ScoresToJson(m.under_overhang)}};
  if (!m.seen_facade.thresholds_m.empty()) j["seen_facade"] = ScoresToJson(m.seen_facade);
  const FacadeOffsets& f = m.facade_offset;
  j["facade_offset"] = {{"max_offset_m", f.max_offset_m},       {"num_samples", f.num_samples},
                        {"num_crossed", f.num_crossed},         {"p25_m", f.p25_m},
                        {"median_m", f.median_m},               {"p75_m", f.p75_m},
                        {"outside_0.5m", f.outside_fraction},   {"inside_0.5m", f.inside_fraction}};
  return j;
}

json SurfaceEvaluationToJson(const SurfaceEvaluation& e) {
  json j = {{"dsm", DsmEvaluationToJson(e.dsm)}};
  if (!e.mesh3d.all.thresholds_m.empty()) j["mesh3d"] = Mesh3dMetricsToJson(e.mesh3d);
  return j;
}

json SceneEvaluationToJson(const SceneEvaluation& e) {
  json j;
  j["grid"] = {{"width", e.grid_width}, {"height", e.grid_height}, {"gsd_m", e.gsd_m},
               {"roof_mask_cells", e.num_mask_cells}};
  j["initial"] = SurfaceEvaluationToJson(e.initial);
  j["result"] = SurfaceEvaluationToJson(e.result);
  j["ratio_result_over_initial"] = Ratios(j["initial"], j["result"]);
  if (!e.error_by_sigma.empty()) {
    json bins = json::array();
    for (const SigmaBin& b : e.error_by_sigma)
      bins.push_back({{"sigma_min_m", std::isfinite(b.sigma_min_m) ? json(b.sigma_min_m) : json("inf")},
                      {"sigma_max_m", std::isfinite(b.sigma_max_m) ? json(b.sigma_max_m) : json("inf")},
                      {"vertices", b.vertices},
                      {"median_error_m", b.median_error_m},
                      {"p90_error_m", b.p90_error_m}});
    j["result_error_by_height_sigma"] = bins;
  }
  return j;
}

std::string FormatSceneEvaluation(const SceneEvaluation& e) {
  std::vector<Row> rows;
  AddDsmRows(rows, "2.5D roofs raw    ", [](const SurfaceEvaluation& s) -> const DsmMetrics& { return s.dsm.mask_raw; });
  AddDsmRows(rows, "2.5D roofs aligned", [](const SurfaceEvaluation& s) -> const DsmMetrics& { return s.dsm.mask_aligned; });
  AddDsmRows(rows, "2.5D all raw      ", [](const SurfaceEvaluation& s) -> const DsmMetrics& { return s.dsm.all_raw; });
  AddDsmRows(rows, "2.5D all aligned  ", [](const SurfaceEvaluation& s) -> const DsmMetrics& { return s.dsm.all_aligned; });
  if (!e.result.mesh3d.all.thresholds_m.empty()) {
    Add3dRows(rows, "3D all   ", e.result.mesh3d.all, [](const SurfaceEvaluation& s) -> const Mesh3dScores& { return s.mesh3d.all; });
    Add3dRows(rows, "3D facade", e.result.mesh3d.facade, [](const SurfaceEvaluation& s) -> const Mesh3dScores& { return s.mesh3d.facade; });
    Add3dRows(rows, "3D under overhangs", e.result.mesh3d.under_overhang, [](const SurfaceEvaluation& s) -> const Mesh3dScores& { return s.mesh3d.under_overhang; });
    const auto offset = [&](std::string name, std::function<double(const FacadeOffsets&)> f,
                            bool pct) {
      rows.push_back({"3D facade offset (+ outside) " + name,
                      [f](const SurfaceEvaluation& s) { return f(s.mesh3d.facade_offset); }, pct});
    };
    offset("median [m]", [](const FacadeOffsets& f) { return f.median_m; }, false);
    offset("p25 [m]", [](const FacadeOffsets& f) { return f.p25_m; }, false);
    offset("p75 [m]", [](const FacadeOffsets& f) { return f.p75_m; }, false);
    offset("outside >0.5m", [](const FacadeOffsets& f) { return f.outside_fraction; }, true);
    offset("inside >0.5m", [](const FacadeOffsets& f) { return f.inside_fraction; }, true);
    if (!e.result.mesh3d.seen_facade.thresholds_m.empty())
      Add3dRows(rows, "3D facade seen by 2 views", e.result.mesh3d.seen_facade, [](const SurfaceEvaluation& s) -> const Mesh3dScores& { return s.mesh3d.seen_facade; });
  }
  std::string out = fmt::format("grid {}x{} cells, GSD {:g} m, {} roof-mask cells\n", e.grid_width,
                                e.grid_height, e.gsd_m, e.num_mask_cells);
  out += fmt::format("{:<44} {:>10} {:>10} {:>8}\n", "metric", "initial", "result", "ratio");
  for (const Row& r : rows) {
    const double a = r.get(e.initial), b = r.get(e.result);
    const double s = r.percent ? 100.0 : 1.0;
    const std::string ratio = a != 0 ? fmt::format("{:.3f}", b / a) : "-";
    out += fmt::format("{:<44} {:>9.3f}{} {:>9.3f}{} {:>8}\n", r.label, a * s, r.percent ? "%" : " ",
                       b * s, r.percent ? "%" : " ", ratio);
  }
  auto align = [](const Alignment& a) {
    return fmt::format("dx {:+.2f} dy {:+.2f} dz {:+.3f} m", a.dx_m, a.dy_m, a.dz_m);
  };
  out += "alignment initial: " + align(e.initial.dsm.alignment) + "\n";
  out += "alignment result:  " + align(e.result.dsm.alignment) + "\n";
  out += "3D counts (result/truth samples): all initial " +
         fmt::format("{}/{}, result {}/{}; facade initial {}/{}, result {}/{}\n",
                     e.initial.mesh3d.all.num_result_samples, e.initial.mesh3d.all.num_truth_samples,
                     e.result.mesh3d.all.num_result_samples, e.result.mesh3d.all.num_truth_samples,
                     e.initial.mesh3d.facade.num_result_samples, e.initial.mesh3d.facade.num_truth_samples,
                     e.result.mesh3d.facade.num_result_samples, e.result.mesh3d.facade.num_truth_samples);
  if (!e.error_by_sigma.empty()) {
    out += "result vertices by their height sigma from the images (deciles, then unseen):\n";
    out += fmt::format("  {:>19} {:>9} {:>14} {:>11}\n", "sigma [m]", "vertices", "median error", "p90 error");
    for (const SigmaBin& b : e.error_by_sigma)
      out += fmt::format("  {:>8.3f} - {:>8.3f} {:>9} {:>12.3f} m {:>9.3f} m\n", b.sigma_min_m,
                         b.sigma_max_m, b.vertices, b.median_error_m, b.p90_error_m);
  }
  return out;
}

}  // namespace satmesh::cli
