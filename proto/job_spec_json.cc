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

OptionValue OptionFromJson(OptionType type, const json& v, const std::string& path) {
  switch (type) {
    case OptionType::kBool: return Boolean(v, path);
    case OptionType::kInt: return Integer(v, path);
    case OptionType::kDouble: return Number(v, path);
  }
  Bad(path, "unknown option type");
}

// Sets the table's options from the object `o` at `path`; a key not in the table is
// `unknown` ("unknown option"). The caller checks the result.
template <typename Info, typename Options>
void ParseOptionTable(const json& o, const std::string& path, const std::vector<Info>& table,
                      const char* unknown, Options* options) {
  Object(o, path);
  for (const auto& [key, v] : o.items()) {
    const std::string key_path = path + "." + key;
    const Info* option = FindOption(table, key);
    if (option == nullptr) Bad(key_path, unknown);
    option->Set(options, OptionFromJson(option->type(), v, key_path));
  }
}

void ParseOptions(const json& o, RefineOptions* r) {
  ParseOptionTable(o, "options", RefineOptionTable(), "unknown option", r);
  const std::string problem = r->Check();  // names the option by its wire name
  if (!problem.empty()) ThrowError(ErrorCode::kInvalidArgument, "options." + problem);
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
  ParseOptionTable(t, "tiling", TilingOptionTable(), "unknown field", tiling);
  const std::string problem = tiling->Check();  // "tiling.<wire name> must be ..."
  if (!problem.empty()) ThrowError(ErrorCode::kInvalidArgument, problem);
}

template <typename Info>
json OptionSchema(const Info& option) {
  const bool integer = option.type() == OptionType::kInt;
  const auto bound = [&](double b) { return integer ? json(int(b)) : json(b); };
  json schema = {
      {"type", option.type() == OptionType::kBool ? "boolean" : integer ? "integer" : "number"},
      {"default", std::visit([](auto v) { return json(v); }, option.Default())},
      {"description", option.help}};
  const OptionRange& r = option.range;
  if (r.min) schema[r.min_exclusive ? "exclusiveMinimum" : "minimum"] = bound(*r.min);
  if (r.max) schema[r.max_exclusive ? "exclusiveMaximum" : "maximum"] = bound(*r.max);
  return schema;
}

template <typename Info>
json OptionTableSchema(const std::vector<Info>& table) {
  json properties = json::object();
  for (const Info& option : table) properties[std::string(option.name)] = OptionSchema(option);
  return properties;
}

// Throws for a --set key whose option is not in the table, listing the table's names.
template <typename Info>
void RequireOption(const std::vector<Info>& table, const std::string& name, const std::string& key,
                   const std::string& what) {
  if (FindOption(table, name) != nullptr) return;
  std::string names;
  for (const Info& option : table) names += (names.empty() ? "" : ", ") + std::string(option.name);
  ThrowError(ErrorCode::kInvalidArgument,
             "--set " + key + ": unknown option; the " + what + " options are " + names);
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
  } else if (dot == std::string::npos || key.substr(0, dot) == "options") {
    const std::string name = dot == std::string::npos ? key : key.substr(dot + 1);
    RequireOption(RefineOptionTable(), name, key, "refinement");
    (*job)["options"][name] = parsed;  // a refinement option
  } else {
    if (key.substr(0, dot) == "tiling")
      RequireOption(TilingOptionTable(), key.substr(dot + 1), key, "tiling");
    (*job)[key.substr(0, dot)][key.substr(dot + 1)] = parsed;  // e.g. tiling.size_m
  }
}

json RefineOptionsSchema() { return OptionTableSchema(RefineOptionTable()); }
json TilingOptionsSchema() { return OptionTableSchema(TilingOptionTable()); }

}  // namespace satmesh::proto
