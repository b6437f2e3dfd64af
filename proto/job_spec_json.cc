#include "proto/job_spec_json.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>

#include "core/common/error.h"

namespace satmesh::proto {
namespace {

using nlohmann::json;

[[noreturn]] void Bad(const std::string& path, const std::string& what) {
  ThrowError(ErrorCode::kInvalidArgument, path + ": " + what);
}

const json& Object(const json& j, const std::string& path) {
  if (!j.is_object()) Bad(path, "expected an object");
  return j;
}

void CheckKeys(const json& j, const std::string& path, std::initializer_list<const char*> allowed) {
  for (const auto& [key, value] : j.items()) {
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a;
    if (!ok) Bad(path.empty() ? key : path + "." + key, "unknown field");
  }
}

std::string String(const json& j, const std::string& path) {
  if (!j.is_string() || j.get<std::string>().empty()) Bad(path, "expected a non-empty string");
  return j.get<std::string>();
}

double Number(const json& j, const std::string& path) {
  if (!j.is_number()) Bad(path, "expected a number");
  return j.get<double>();
}

int Integer(const json& j, const std::string& path) {
  if (!j.is_number_integer()) Bad(path, "expected an integer");
  return j.get<int>();
}

bool Boolean(const json& j, const std::string& path) {
  if (!j.is_boolean()) Bad(path, "expected true or false");
  return j.get<bool>();
}

std::string Resolve(const std::string& href, const std::string& base_dir) {
  if (href.rfind("/vsi", 0) == 0 || std::filesystem::path(href).is_absolute()) return href;
  return (std::filesystem::path(base_dir) / href).lexically_normal().string();
}

void ParseOptions(const json& o, RefineOptions* r) {
  Object(o, "options");
  for (const auto& [key, v] : o.items()) {
    const std::string path = "options." + key;
    if (key == "levels") r->levels = Integer(v, path);
    else if (key == "max_coarse_edge_m") r->max_coarse_edge_m = Number(v, path);
    else if (key == "iterations_per_level") r->iterations_per_level = Integer(v, path);
    else if (key == "alpha") r->alpha = Number(v, path);
    else if (key == "beta") r->beta = Number(v, path);
    else if (key == "step") r->step = Number(v, path);
    else if (key == "max_step_gsd") r->max_step_gsd = Number(v, path);
    else if (key == "zncc_window_radius") r->zncc_window_radius = Integer(v, path);
    else if (key == "min_window_valid") r->min_window_valid = Number(v, path);
    else if (key == "variance_floor") r->variance_floor = Number(v, path);
    else if (key == "noise_variance_factor") r->noise_variance_factor = Number(v, path);
    else if (key == "visibility_tolerance_gsd") r->visibility_tolerance_gsd = Number(v, path);
    else if (key == "min_ray_cos") r->min_ray_cos = Number(v, path);
    else if (key == "virtual_camera_grid_px") r->virtual_camera_grid_px = Integer(v, path);
    else if (key == "rasterize_hit_maps") r->rasterize_hit_maps = Boolean(v, path);
    else if (key == "hit_maps_every") r->hit_maps_every = Integer(v, path);
    else if (key == "coarse_edge_px") r->coarse_edge_px = Number(v, path);
    else if (key == "remesh_coarse") r->remesh_coarse = Boolean(v, path);
    else if (key == "alternate_directions") r->alternate_directions = Boolean(v, path);
    else if (key == "restart_from_initial") r->restart_from_initial = Boolean(v, path);
    else if (key == "normalize_by_pair_count") r->normalize_by_pair_count = Boolean(v, path);
    else if (key == "min_height_confidence") r->min_height_confidence = Number(v, path);
    else if (key == "height_sigma_gsd") r->height_sigma_gsd = Number(v, path);
    else if (key == "hold_unseen") r->hold_unseen = Boolean(v, path);
    else if (key == "hold_boundary_xy") r->hold_boundary_xy = Boolean(v, path);
    else if (key == "estimate_bias") r->estimate_bias = Boolean(v, path);
    else if (key == "min_pair_angle_deg") r->pairs.min_angle_deg = Number(v, path);
    else if (key == "max_pair_angle_deg") r->pairs.max_angle_deg = Number(v, path);
    else if (key == "optimal_pair_angle_deg") r->pairs.optimal_angle_deg = Number(v, path);
    else if (key == "min_pair_overlap") r->pairs.min_overlap = Number(v, path);
    else if (key == "pair_partners_per_view") r->pairs.partners_per_view = Integer(v, path);
    else if (key == "max_pairs_per_image") r->pairs.max_pairs_per_image = Integer(v, path);
    else if (key == "max_pairs") r->pairs.max_pairs = Integer(v, path);
    else if (key == "min_contrast") r->pairs.min_contrast = Number(v, path);
    else Bad(path, "unknown option");
  }
  const std::string problem = r->Check();
  if (!problem.empty()) Bad("options", problem);
}

Eigen::Vector2d Point(const json& j, const std::string& path) {
  if (!j.is_array() || j.size() != 2) Bad(path, "expected [x, y]");
  return {Number(j[0], path + "[0]"), Number(j[1], path + "[1]")};
}

void ParseAoi(const json& a, JobAoi* aoi) {
  Object(a, "aoi");
  CheckKeys(a, "aoi", {"bbox", "polygon", "crs"});
  if (a.contains("bbox") == a.contains("polygon")) Bad("aoi", "give exactly one of bbox, polygon");
  if (a.contains("bbox")) {
    const json& b = a["bbox"];
    if (!b.is_array() || b.size() != 4) Bad("aoi.bbox", "expected [xmin, ymin, xmax, ymax]");
    double v[4];
    for (int k = 0; k < 4; ++k) v[k] = Number(b[k], "aoi.bbox[" + std::to_string(k) + "]");
    if (!(v[0] < v[2] && v[1] < v[3])) Bad("aoi.bbox", "expected xmin < xmax and ymin < ymax");
    aoi->polygon = {{v[0], v[1]}, {v[2], v[1]}, {v[2], v[3]}, {v[0], v[3]}};
  } else {
    const json& p = a["polygon"];
    if (!p.is_array() || p.size() < 3) Bad("aoi.polygon", "expected >= 3 points [x, y]");
    for (size_t i = 0; i < p.size(); ++i)
      aoi->polygon.push_back(Point(p[i], "aoi.polygon[" + std::to_string(i) + "]"));
  }
  if (a.contains("crs")) aoi->crs = String(a["crs"], "aoi.crs");
}

void ParseTiling(const json& t, TilingOptions* tiling) {
  Object(t, "tiling");
  CheckKeys(t, "tiling", {"size_m", "overlap_m", "workers", "memory_budget_mb"});
  if (t.contains("size_m")) tiling->tile_size_m = Number(t["size_m"], "tiling.size_m");
  if (t.contains("overlap_m")) tiling->overlap_m = Number(t["overlap_m"], "tiling.overlap_m");
  if (t.contains("workers")) tiling->workers = Integer(t["workers"], "tiling.workers");
  if (t.contains("memory_budget_mb"))
    tiling->memory_budget_mb = Number(t["memory_budget_mb"], "tiling.memory_budget_mb");
  const std::string problem = tiling->Check();
  if (!problem.empty()) Bad("tiling", problem);
}

}  // namespace

JobSpec JobSpecFromJson(const json& job, const std::string& base_dir) {
  Object(job, "job");
  CheckKeys(job, "", {"images", "initial", "outputs", "options", "aoi", "tiling"});
  JobSpec spec;
  if (!job.contains("images")) Bad("images", "required");
  const json& images = job["images"];
  if (!images.is_array()) Bad("images", "expected an array");
  if (images.size() < 2) Bad("images", "need at least 2 images, got " + std::to_string(images.size()));
  for (size_t i = 0; i < images.size(); ++i) {
    const std::string path = "images[" + std::to_string(i) + "]";
    Object(images[i], path);
    CheckKeys(images[i], path, {"href", "bias"});
    if (!images[i].contains("href")) Bad(path + ".href", "required");
    JobImage image;
    image.path = Resolve(String(images[i]["href"], path + ".href"), base_dir);
    if (images[i].contains("bias")) {
      const json& b = images[i]["bias"];
      if (!b.is_array() || b.size() != 2) Bad(path + ".bias", "expected [col, row]");
      image.bias_col_row_px = {Number(b[0], path + ".bias[0]"), Number(b[1], path + ".bias[1]")};
    }
    spec.images.push_back(image);
  }
  if (!job.contains("initial")) Bad("initial", "required");
  Object(job["initial"], "initial");
  const json& initial = job["initial"];
  CheckKeys(initial, "initial", {"dsm", "mesh", "crs", "fill_holes_m"});
  if (!initial.contains("dsm") && !initial.contains("mesh")) Bad("initial", "needs dsm or mesh (or both)");
  if (initial.contains("dsm")) spec.initial_dsm = Resolve(String(initial["dsm"], "initial.dsm"), base_dir);
  if (initial.contains("mesh"))
    spec.initial_mesh.path = Resolve(String(initial["mesh"], "initial.mesh"), base_dir);
  if (initial.contains("crs")) {
    if (!initial.contains("mesh")) Bad("initial.crs", "is the initial mesh's CRS; there is no initial.mesh");
    spec.initial_mesh.crs = String(initial["crs"], "initial.crs");
  }
  if (initial.contains("fill_holes_m"))
    spec.fill_holes_m = Number(initial["fill_holes_m"], "initial.fill_holes_m");
  if (job.contains("outputs")) {
    Object(job["outputs"], "outputs");
    CheckKeys(job["outputs"], "outputs", {"crs", "dsm_resolution_m"});
    if (job["outputs"].contains("crs")) spec.output_crs = String(job["outputs"]["crs"], "outputs.crs");
    if (job["outputs"].contains("dsm_resolution_m"))
      spec.dsm_resolution_m = Number(job["outputs"]["dsm_resolution_m"], "outputs.dsm_resolution_m");
  }
  if (job.contains("aoi")) ParseAoi(job["aoi"], &spec.aoi);
  if (job.contains("tiling")) ParseTiling(job["tiling"], &spec.tiling);
  if (job.contains("options")) ParseOptions(job["options"], &spec.refine);
  const std::string problem = spec.Check();
  if (!problem.empty()) Bad("job", problem);
  return spec;
}

JobSpec ReadJobFile(const std::string& path) {
  std::ifstream in(path);
  SATMESH_CHECK(in.good(), ErrorCode::kNotFound, "job file '" + path + "' cannot be opened");
  json job;
  try {
    job = json::parse(in);
  } catch (const json::parse_error& e) {
    ThrowError(ErrorCode::kInvalidArgument, "job file '" + path + "': invalid JSON: " + e.what());
  }
  return JobSpecFromJson(job, std::filesystem::path(path).parent_path().string());
}

void ApplyOptionOverride(json* job, const std::string& key_equals_value) {
  const auto eq = key_equals_value.find('=');
  SATMESH_CHECK(eq != std::string::npos && eq > 0, ErrorCode::kInvalidArgument,
                "--set expects key=value, got '" + key_equals_value + "'");
  const std::string key = key_equals_value.substr(0, eq), value = key_equals_value.substr(eq + 1);
  json parsed;
  try {
    parsed = json::parse(value);
  } catch (const json::parse_error&) {
    parsed = value;
  }
  const auto dot = key.find('.');
  if (key == "aoi" || key == "tiling" || key == "outputs" || key == "initial") {
    (*job)[key] = parsed;  // a whole top-level object, e.g. aoi={"bbox": [...]}
  } else if (dot == std::string::npos) {
    (*job)["options"][key] = parsed;  // a refinement option
  } else {
    (*job)[key.substr(0, dot)][key.substr(dot + 1)] = parsed;  // e.g. tiling.size_m
  }
}

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
                   {"gsd_m", l.gsd_m},
                   {"vertices", l.num_vertices},
                   {"faces", l.num_faces},
                   {"mean_zncc", l.mean_zncc},
                   {"mean_zncc_start", l.mean_zncc.empty() ? 0.0 : l.mean_zncc.front()},
                   {"mean_zncc_end", l.mean_zncc.empty() ? 0.0 : l.mean_zncc.back()},
                   {"initial_zncc", l.initial_zncc},  // NaN (null): not compared
                   {"restarted_from_initial", l.restarted},
                   {"time_s", {{"hit_maps", l.times.hit_maps_s},
                               {"intersect", l.times.intersect_s},
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
    s.gsd_m = l.value("gsd_m", 0.0);
    s.num_vertices = l.value("vertices", 0);
    s.num_faces = l.value("faces", 0);
    s.mean_zncc = l.value("mean_zncc", std::vector<double>{});
    s.initial_zncc = NumberOr(l, "initial_zncc", std::numeric_limits<double>::quiet_NaN());
    s.restarted = l.value("restarted_from_initial", false);
    if (l.contains("time_s")) {
      const json& t = l["time_s"];
      s.times.hit_maps_s = t.value("hit_maps", 0.0);
      s.times.intersect_s = t.value("intersect", 0.0);
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
  std::map<int, std::pair<LevelStats, std::vector<double>>> levels;    // by level: sum, weight per iteration
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
      auto& [sum, weight] = levels[l.level];
      const bool first = weight.empty() && sum.iterations == 0 && sum.num_faces == 0;
      sum.level = l.level;
      sum.iterations = std::max(sum.iterations, l.iterations);
      sum.num_vertices += l.num_vertices;
      sum.num_faces += l.num_faces;
      sum.gsd_m += l.gsd_m;
      sum.restarted = sum.restarted || l.restarted;
      sum.initial_check_s += l.initial_check_s;
      sum.level_s += l.level_s;
      sum.times.hit_maps_s += l.times.hit_maps_s;
      sum.times.intersect_s += l.times.intersect_s;
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
  for (auto& [level, value] : levels) {
    auto& [sum, weight] = value;
    int tiles_at_level = 0;
    for (const auto& t : tiles)
      for (const auto& l : t.refine.levels) tiles_at_level += t.ok && l.level == level;
    sum.gsd_m /= std::max(1, tiles_at_level);
    for (size_t k = 0; k < sum.mean_zncc.size(); ++k) sum.mean_zncc[k] /= weight[k];
    out.levels.push_back(sum);
  }
  // Coarse to fine, as a tile lists them.
  std::sort(out.levels.begin(), out.levels.end(), [](const auto& a, const auto& b) { return a.level > b.level; });
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
  const std::string name = String(j.at("name"), "tile.name");
  for (size_t i = 0; i < plan.tiles.size() && t.index < 0; ++i)
    if (plan.tiles[i].Name() == name) t.index = int(i);
  if (t.index < 0) Bad("tile.name", "'" + name + "' is not a tile of the plan");
  t.name = name;
  t.ok = j.at("status") == "successful";
  if (!t.ok) {
    t.error = j.at("error").value("message", "");
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

json RefineMetricsToJson(const JobOutputs& outputs) { return JobMetricsToJson(outputs); }

void WriteJobJson(const JobOutputs& outputs, const std::string& out_dir) {
  WriteJsonAtomically(std::filesystem::path(out_dir) / "tileset.json", TilesetToJson(outputs.assembly.tileset));
  WriteJsonAtomically(std::filesystem::path(out_dir) / "metrics.json", JobMetricsToJson(outputs));
}

}  // namespace satmesh::proto
