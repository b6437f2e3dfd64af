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
    else if (key == "flat_tolerance_gsd") r->flat_tolerance_gsd = Number(v, path);
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

}  // namespace satmesh::proto
