#include "proto/job_spec_json.h"

#include <filesystem>
#include <fstream>

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
    else if (key == "iterations_per_level") r->iterations_per_level = Integer(v, path);
    else if (key == "alpha") r->alpha = Number(v, path);
    else if (key == "beta") r->beta = Number(v, path);
    else if (key == "step") r->step = Number(v, path);
    else if (key == "max_step_gsd") r->max_step_gsd = Number(v, path);
    else if (key == "zncc_window_radius") r->zncc_window_radius = Integer(v, path);
    else if (key == "min_window_valid") r->min_window_valid = Number(v, path);
    else if (key == "variance_floor") r->variance_floor = Number(v, path);
    else if (key == "visibility_tolerance_gsd") r->visibility_tolerance_gsd = Number(v, path);
    else if (key == "min_ray_cos") r->min_ray_cos = Number(v, path);
    else if (key == "virtual_camera_grid_px") r->virtual_camera_grid_px = Integer(v, path);
    else if (key == "coarse_edge_px") r->coarse_edge_px = Number(v, path);
    else if (key == "remesh_coarse") r->remesh_coarse = Boolean(v, path);
    else if (key == "normalize_by_pair_count") r->normalize_by_pair_count = Boolean(v, path);
    else if (key == "hold_boundary_xy") r->hold_boundary_xy = Boolean(v, path);
    else if (key == "min_pair_angle_deg") r->pairs.min_angle_deg = Number(v, path);
    else if (key == "max_pair_angle_deg") r->pairs.max_angle_deg = Number(v, path);
    else if (key == "max_pairs_per_image") r->pairs.max_pairs_per_image = Integer(v, path);
    else if (key == "min_contrast") r->pairs.min_contrast = Number(v, path);
    else Bad(path, "unknown option");
  }
  const std::string problem = r->Check();
  if (!problem.empty()) Bad("options", problem);
}

}  // namespace

JobSpec JobSpecFromJson(const json& job, const std::string& base_dir) {
  Object(job, "job");
  CheckKeys(job, "", {"images", "initial", "outputs", "options"});
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
  CheckKeys(job["initial"], "initial", {"dsm"});
  if (!job["initial"].contains("dsm")) Bad("initial.dsm", "required");
  spec.initial_dsm = Resolve(String(job["initial"]["dsm"], "initial.dsm"), base_dir);
  if (job.contains("outputs")) {
    Object(job["outputs"], "outputs");
    CheckKeys(job["outputs"], "outputs", {"crs"});
    if (job["outputs"].contains("crs")) spec.output_crs = String(job["outputs"]["crs"], "outputs.crs");
  }
  if (job.contains("options")) ParseOptions(job["options"], &spec.refine);
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
  (*job)["options"][key] = parsed;
}

json RefineMetricsToJson(const JobOutputs& outputs) {
  const RefineResult& r = outputs.refine;
  json levels = json::array();
  for (const auto& l : r.levels) {
    levels.push_back({{"level", l.level},
                      {"iterations", l.iterations},
                      {"gsd_m", l.gsd_m},
                      {"vertices", l.num_vertices},
                      {"faces", l.num_faces},
                      {"mean_zncc", l.mean_zncc},
                      {"mean_zncc_start", l.mean_zncc.empty() ? 0.0 : l.mean_zncc.front()},
                      {"mean_zncc_end", l.mean_zncc.empty() ? 0.0 : l.mean_zncc.back()},
                      {"time_s", {{"raycast", l.times.raycast_s},
                                  {"gradient", l.times.gradient_s},
                                  {"smoothness", l.times.smoothness_s},
                                  {"update", l.times.update_s},
                                  {"level", l.level_s}}}});
  }
  json pairs = json::array();
  for (const auto& [i, j] : r.pairs) pairs.push_back({i, j});
  return {{"views", outputs.view_names},
          {"pairs", pairs},
          {"gsd_m", r.gsd_m},
          {"levels", levels},
          {"time_s", {{"prepare", outputs.prepare_s}, {"refine", r.total_s}, {"write", outputs.write_s}}},
          {"outputs", {{"mesh", "mesh.ply"}, {"dsm", "dsm.tif"}}}};
}

}  // namespace satmesh::proto
