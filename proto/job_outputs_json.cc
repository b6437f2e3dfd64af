// The job's outputs as JSON: metrics.json (per tile and totals) and tileset.json (3D
// Tiles 1.1); the parsing of the job spec is in job_spec_json.cc.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

#include "core/common/error.h"
#include "proto/job_spec_json.h"

namespace satmesh::proto {

using nlohmann::json;

namespace {

json Array(const auto& values) {
  json a = json::array();
  for (const auto& v : values) a.push_back(v);
  return a;
}

json LevelsToJson(const std::vector<LevelStats>& levels) {
  json out = json::array();
  for (const auto& l : levels) {
    out.push_back({{"level", l.level},
                   {"iterations", l.iterations},
                   {"pair_directions", l.pair_directions},
                   {"gsd_m", l.gsd_m},
                   {"vertices", l.num_vertices},
                   {"faces", l.num_faces},
                   {"mean_zncc", l.mean_zncc},
                   {"mean_zncc_start", l.mean_zncc.empty() ? 0.0 : l.mean_zncc.front()},
                   {"mean_zncc_end", l.mean_zncc.empty() ? 0.0 : l.mean_zncc.back()},
                   {"initial_zncc", l.initial_zncc},  // NaN (null): not compared
                   {"restarted_from_initial", l.restarted},
                   {"crease_pass", l.crease_pass},
                   {"time_s", {{"hit_maps", l.times.hit_maps_s},
                               {"intersect", l.times.intersect_s},
                               {"sunlight", l.times.sunlight_s},
                               {"gradient", l.times.gradient_s},
                               {"smoothness", l.times.smoothness_s},
                               {"update", l.times.update_s},
                               {"initial_check", l.initial_check_s},
                               {"level", l.level_s}}}});
  }
  return out;
}

json PairsToJson(const std::vector<StereoPair>& pairs) {
  json out = json::array();
  for (const auto& p : pairs)
    out.push_back({{"views", {p.i, p.j}}, {"angle_deg", p.angle_deg}, {"overlap", p.overlap}, {"score", p.score}});
  return out;
}

double NumberOr(const json& j, const char* key, double fallback) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : fallback;
}

std::vector<LevelStats> LevelsFromJson(const json& levels) {
  std::vector<LevelStats> out;
  for (const auto& l : levels) {
    LevelStats s;
    s.level = l.value("level", 0);
    s.iterations = l.value("iterations", 0);
    s.pair_directions = l.value("pair_directions", 0);
    s.gsd_m = l.value("gsd_m", 0.0);
    s.num_vertices = l.value("vertices", 0);
    s.num_faces = l.value("faces", 0);
    s.mean_zncc = l.value("mean_zncc", std::vector<double>{});
    s.initial_zncc = NumberOr(l, "initial_zncc", std::numeric_limits<double>::quiet_NaN());
    s.restarted = l.value("restarted_from_initial", false);
    s.crease_pass = l.value("crease_pass", false);
    if (l.contains("time_s")) {
      const json& t = l["time_s"];
      s.times.hit_maps_s = t.value("hit_maps", 0.0);
      s.times.intersect_s = t.value("intersect", 0.0);
      s.times.sunlight_s = t.value("sunlight", 0.0);
      s.times.gradient_s = t.value("gradient", 0.0);
      s.times.smoothness_s = t.value("smoothness", 0.0);
      s.times.update_s = t.value("update", 0.0);
      s.initial_check_s = t.value("initial_check", 0.0);
      s.level_s = t.value("level", 0.0);
    }
    out.push_back(s);
  }
  return out;
}

// The job-level refinement summary of a tiled job, from its successful tiles: views (the
// union, in order of appearance), pairs (by view name; angle, overlap, score averaged over
// the tiles that selected them; "tiles": how many), the GSD (mean), the candidate pairs
// (most of any tile) and per level: vertices, faces, iterations and times summed, GSD
// averaged, mean ZNCC per iteration weighted by each tile's faces. A single tile's summary
// is its own.
struct JobRefineSummary {
  std::vector<std::string> views;
  json pairs = json::array();
  double gsd_m = 0;
  int candidate_pairs = 0;
  std::vector<LevelStats> levels;
};

JobRefineSummary SummariseTiles(const std::vector<TileResult>& tiles) {
  JobRefineSummary out;
  std::map<std::pair<int, int>, std::pair<StereoPair, int>> pairs;  // by job view index
  // Per level (its crease pass apart): the tiles' sum, the ZNCC curve's weight per
  // iteration, and how many tiles ran it.
  struct LevelSum {
    LevelStats sum;
    std::vector<double> weight;
    int tiles = 0;
  };
  std::map<std::pair<int, bool>, LevelSum> levels;
  int n = 0;
  for (const auto& t : tiles) {
    if (!t.ok) continue;
    ++n;
    out.gsd_m += t.refine.gsd_m;
    out.candidate_pairs = std::max(out.candidate_pairs, t.refine.candidate_pairs);
    std::vector<int> index;  // tile view -> job view
    for (const auto& name : t.view_names) {
      const auto it = std::find(out.views.begin(), out.views.end(), name);
      index.push_back(int(it - out.views.begin()));
      if (it == out.views.end()) out.views.push_back(name);
    }
    for (const auto& p : t.refine.pair_details) {
      if (p.i < 0 || p.j < 0 || p.i >= int(index.size()) || p.j >= int(index.size())) continue;
      const auto key = std::minmax(index[p.i], index[p.j]);
      auto& [sum, count] = pairs[key];
      sum.i = key.first, sum.j = key.second;
      sum.angle_deg += p.angle_deg, sum.overlap += p.overlap, sum.score += p.score;
      ++count;
    }
    for (const auto& l : t.refine.levels) {
      auto& [sum, weight, tiles_at_level] = levels[{l.level, l.crease_pass}];
      const bool first = tiles_at_level++ == 0;
      sum.level = l.level;
      sum.crease_pass = l.crease_pass;
      sum.iterations = std::max(sum.iterations, l.iterations);
      sum.num_vertices += l.num_vertices;
      sum.num_faces += l.num_faces;
      sum.gsd_m += l.gsd_m;
      sum.restarted = sum.restarted || l.restarted;
      sum.initial_check_s += l.initial_check_s;
      sum.level_s += l.level_s;
      sum.times.hit_maps_s += l.times.hit_maps_s;
      sum.times.intersect_s += l.times.intersect_s;
      sum.times.sunlight_s += l.times.sunlight_s;
      sum.times.gradient_s += l.times.gradient_s;
      sum.times.smoothness_s += l.times.smoothness_s;
      sum.times.update_s += l.times.update_s;
      const double w = std::max(1, l.num_faces);
      if (first) sum.mean_zncc.assign(l.mean_zncc.size(), 0.0), weight.assign(l.mean_zncc.size(), 0.0);
      const size_t k_max = std::min(sum.mean_zncc.size(), l.mean_zncc.size());
      sum.mean_zncc.resize(k_max), weight.resize(k_max);  // tiles that stopped early: common part
      for (size_t k = 0; k < k_max; ++k) sum.mean_zncc[k] += w * l.mean_zncc[k], weight[k] += w;
      // Compared per tile: one tile's value stands, several have none in common.
      sum.initial_zncc = first ? l.initial_zncc : std::numeric_limits<double>::quiet_NaN();
    }
  }
  if (n > 0) out.gsd_m /= n;
  for (const auto& [key, value] : pairs) {
    const auto& [sum, count] = value;
    out.pairs.push_back({{"views", {key.first, key.second}}, {"angle_deg", sum.angle_deg / count},
                         {"overlap", sum.overlap / count}, {"score", sum.score / count}, {"tiles", count}});
  }
  for (auto& [key, value] : levels) {
    auto& [sum, weight, tiles_at_level] = value;
    sum.gsd_m /= tiles_at_level;
    for (size_t k = 0; k < sum.mean_zncc.size(); ++k) sum.mean_zncc[k] /= weight[k];
    out.levels.push_back(sum);
  }
  // Coarse to fine, as a tile lists them (the crease pass after level 0).
  std::sort(out.levels.begin(), out.levels.end(), [](const auto& a, const auto& b) {
    return a.level != b.level ? a.level > b.level : !a.crease_pass && b.crease_pass;
  });
  return out;
}

// Estimated RPC bias per view: [[col, row], ...] in full-resolution pixels.
json BiasesToJson(const std::vector<Eigen::Vector2d>& biases) {
  json out = json::array();
  for (const auto& b : biases) out.push_back({b.x(), b.y()});
  return out;
}

json BoxToJson(const Box2d& b) { return {b.xmin, b.ymin, b.xmax, b.ymax}; }

json SeamToJson(const SeamStats& s) {
  return {{"a", s.a}, {"b", s.b}, {"cells", s.cells}, {"median_abs_m", s.median_abs_m},
          {"p95_abs_m", s.p95_abs_m}, {"max_abs_m", s.max_abs_m}, {"mean_m", s.mean_m}};
}

void WriteJsonAtomically(const std::filesystem::path& path, const json& j) {
  const auto tmp = path.string() + ".part";
  {
    std::ofstream out(tmp);
    SATMESH_CHECK(out.good(), ErrorCode::kIo, "cannot write '" + tmp + "'");
    out << j.dump(2) << "\n";
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace

json TileResultToJson(const JobPlan& plan, const TileResult& t) {
  const PlannedTile& p = plan.tiles.at(t.index);
  json j = {{"name", p.Name()}, {"x", p.x}, {"y", p.y}, {"status", t.ok ? "successful" : "failed"},
            {"core_extent", BoxToJson(p.core)}, {"padded_extent", BoxToJson(p.padded)}};
  if (!t.ok) {
    j["error"] = {{"code", ErrorCodeName(t.error_code)}, {"message", t.error}};
    return j;
  }
  j["content"] = TileGlbPath(p);
  j["region"] = Array(t.region);
  j["transform"] = Array(t.transform);
  j["views"] = t.view_names;
  j["dropped_views"] = t.dropped_views;
  j["pairs"] = t.refine.pairs.size();
  j["pair_details"] = PairsToJson(t.refine.pair_details);  // views: indices into "views"
  j["candidate_pairs"] = t.refine.candidate_pairs;
  // RefineOptions::grid_start, flat_edge_px
  j["coarse_start"] = t.refine.grid_start > 0 ? "grid" : t.refine.adaptive_start ? "adaptive" : "remesh";
  j["kept_initial_share"] = t.refine.kept_initial_share;  // keep_initial_sigmas's last step
  j["registration_m"] = {t.refine.registration_m.x(), t.refine.registration_m.y(),
                         t.refine.registration_m.z()};  // its shift to the initial's frame
  j["gsd_m"] = t.refine.gsd_m;
  j["vertices"] = t.core_vertices;
  j["faces"] = t.core_faces;
  j["image_mb"] = t.image_mb;
  j["peak_rss_mb"] = t.peak_rss_mb;
  j["estimated_peak_mb"] = t.estimated_peak_mb;
  j["levels"] = LevelsToJson(t.refine.levels);
  if (!t.view_bias_px.empty()) j["bias_px"] = BiasesToJson(t.view_bias_px);
  j["time_s"] = {{"prepare", t.prepare_s}, {"bias", t.bias_s}, {"refine", t.refine_s},
                 {"write", t.write_s}};
  return j;
}

TileResult TileResultFromJson(const JobPlan& plan, const json& j) {
  TileResult t;
  if (!j.contains("name") || !j["name"].is_string())
    ThrowError(ErrorCode::kInvalidArgument, "tile.name: expected a string");
  const std::string name = j["name"].get<std::string>();
  for (size_t i = 0; i < plan.tiles.size() && t.index < 0; ++i)
    if (plan.tiles[i].Name() == name) t.index = int(i);
  if (t.index < 0) ThrowError(ErrorCode::kInvalidArgument, "tile.name: '" + name + "' is not a tile of the plan");
  t.name = name;
  t.ok = j.at("status") == "successful";
  if (!t.ok) {
    t.error = j.at("error").value("message", "");
    const std::string code = j.at("error").value("code", "internal");
    t.error_code = ErrorCode::kInternal;
    for (ErrorCode c : {ErrorCode::kInvalidArgument, ErrorCode::kInvalidInput, ErrorCode::kNotFound,
                        ErrorCode::kIo, ErrorCode::kNoSpace, ErrorCode::kNotConverged, ErrorCode::kCancelled})
      if (code == ErrorCodeName(c)) t.error_code = c;
    return t;
  }
  t.region = j.at("region").get<std::array<double, 6>>();
  t.transform = j.at("transform").get<std::array<double, 16>>();
  t.view_names = j.value("views", std::vector<std::string>{});
  t.dropped_views = j.value("dropped_views", std::vector<std::string>{});
  t.core_vertices = j.value("vertices", size_t{0});
  t.core_faces = j.value("faces", size_t{0});
  t.image_mb = j.value("image_mb", 0.0);
  t.peak_rss_mb = j.value("peak_rss_mb", 0.0);
  t.refine.gsd_m = j.value("gsd_m", 0.0);
  t.refine.candidate_pairs = j.value("candidate_pairs", 0);
  const std::string coarse_start = j.value("coarse_start", std::string("remesh"));
  t.refine.grid_start = coarse_start == "grid" ? 1 : 0;
  t.refine.adaptive_start = coarse_start == "adaptive";
  t.refine.kept_initial_share = j.value("kept_initial_share", 0.0);
  if (j.contains("registration_m") && j["registration_m"].size() == 3)
    for (int a = 0; a < 3; ++a) t.refine.registration_m[a] = j["registration_m"][a].get<double>();
  for (const auto& p : j.value("pair_details", json::array())) {
    StereoPair pair;
    pair.i = p.at("views").at(0).get<int>();
    pair.j = p.at("views").at(1).get<int>();
    pair.angle_deg = p.value("angle_deg", 0.0);
    pair.overlap = p.value("overlap", 0.0);
    pair.score = p.value("score", 0.0);
    t.refine.pair_details.push_back(pair);
    t.refine.pairs.emplace_back(pair.i, pair.j);
  }
  t.refine.levels = LevelsFromJson(j.value("levels", json::array()));
  for (const auto& b : j.value("bias_px", json::array())) t.view_bias_px.emplace_back(b.at(0).get<double>(), b.at(1).get<double>());
  t.estimated_peak_mb = j.value("estimated_peak_mb", 0.0);
  if (j.contains("time_s")) {
    t.prepare_s = j["time_s"].value("prepare", 0.0);
    t.bias_s = j["time_s"].value("bias", 0.0);
    t.refine_s = j["time_s"].value("refine", 0.0);
    t.write_s = j["time_s"].value("write", 0.0);
  }
  return t;
}

json TilesetToJson(const Tileset& ts) {
  json children = json::array();
  for (const auto& t : ts.tiles) {
    children.push_back({{"boundingVolume", {{"region", Array(t.region)}}},
                        {"geometricError", t.geometric_error},
                        {"transform", Array(t.transform)},
                        {"content", {{"uri", t.uri}}}});
  }
  json root = {{"boundingVolume", {{"region", Array(ts.region)}}},
               {"geometricError", ts.geometric_error},
               {"refine", "ADD"},
               {"children", children}};
  return {{"asset", {{"version", "1.1"}, {"generator", "satmesh"}}},
          {"geometricError", ts.geometric_error},
          {"root", root}};
}

json JobMetricsToJson(const JobOutputs& o) {
  json tiles = json::array();
  double refine_s = 0, max_image_mb = 0;
  for (const auto& t : o.tiles) {
    tiles.push_back(TileResultToJson(o.plan, t));
    refine_s += t.refine_s;
    max_image_mb = std::max(max_image_mb, t.image_mb);
  }
  json seams = json::array();
  for (const auto& s : o.assembly.seams) seams.push_back(SeamToJson(s));
  // One tile: its own refinement (the mesh-holding result where RunJob kept it); several:
  // summed over them (SummariseTiles).
  JobRefineSummary summary;
  if (o.tiles.size() == 1 && !o.refine.levels.empty()) {
    summary.views = o.view_names;
    summary.pairs = PairsToJson(o.refine.pair_details);
    summary.gsd_m = o.refine.gsd_m;
    summary.candidate_pairs = o.refine.candidate_pairs;
    summary.levels = o.refine.levels;
  } else {
    summary = SummariseTiles(o.tiles);
  }
  double peak_rss_mb = o.peak_rss_mb;  // the process's; the server's tiles report their own
  for (const auto& t : o.tiles) peak_rss_mb = std::max(peak_rss_mb, t.peak_rss_mb);
  const double cell = o.plan.dsm.geo_transform[1];
  json metrics = {{"views", summary.views},
          {"pairs", summary.pairs},
          {"candidate_pairs", summary.candidate_pairs},
          {"gsd_m", summary.gsd_m},
          {"levels", LevelsToJson(summary.levels)},
          {"tiling", {{"grid", {o.plan.nx, o.plan.ny}},
                      {"cell_m", cell},
                      {"tile_m", o.plan.tile_cells * cell},
                      {"overlap_m", o.plan.overlap_cells * cell},
                      {"workers", o.workers},
                      {"memory_budget_mb", o.plan.memory_budget_mb},
                      {"automatic", o.plan.auto_tiled}}},
          {"tiles", tiles},
          {"seams", seams},
          {"seams_total", SeamToJson(o.assembly.seams_total)},
          {"totals", {{"tiles", o.tiles.size()},
                      {"successful", o.assembly.tiles_ok},
                      {"failed", o.assembly.tiles_failed},
                      {"vertices", o.assembly.vertices},
                      {"faces", o.assembly.faces},
                      {"max_tile_image_mb", max_image_mb},
                      {"peak_rss_mb", peak_rss_mb}}},
          {"time_s", {{"plan", o.plan_s}, {"bias", o.bias_s}, {"tiles", o.tiles_s}, {"prepare", o.prepare_s},
                      {"refine", refine_s}, {"write", o.write_s}, {"total", o.total_s}}},
          {"outputs", {{"mesh", "mesh.ply"}, {"dsm", "dsm.tif"}, {"tileset", "tileset.json"},
                       {"metrics", "metrics.json"}, {"tiles", "tiles/"}}}};
  // Single-tile jobs: the estimated biases at top level too, next to "views".
  if (o.tiles.size() == 1 && !o.tiles[0].view_bias_px.empty())
    metrics["bias_px"] = BiasesToJson(o.tiles[0].view_bias_px);
  return metrics;
}

json JobBiasesToJson(const JobBiases& b) {
  return {{"bias_px", BiasesToJson(b.bias_px)}, {"tile", b.tile}, {"seconds", b.seconds}};
}

JobBiases JobBiasesFromJson(const json& j) {
  JobBiases b;
  for (const auto& v : j.value("bias_px", json::array())) b.bias_px.emplace_back(v.at(0).get<double>(), v.at(1).get<double>());
  b.tile = j.value("tile", "");
  b.seconds = j.value("seconds", 0.0);
  return b;
}

json RefineMetricsToJson(const JobOutputs& outputs) { return JobMetricsToJson(outputs); }

void WriteJobJson(const JobOutputs& outputs, const std::string& out_dir) {
  WriteJsonAtomically(std::filesystem::path(out_dir) / "tileset.json", TilesetToJson(outputs.assembly.tileset));
  WriteJsonAtomically(std::filesystem::path(out_dir) / "metrics.json", JobMetricsToJson(outputs));
}

}  // namespace satmesh::proto
