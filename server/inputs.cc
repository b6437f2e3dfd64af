#include "server/inputs.h"

#include <filesystem>

#include "core/common/error.h"
#include "server/problem.h"

namespace satmesh::server {
namespace fs = std::filesystem;
namespace {

[[noreturn]] void Forbidden(const std::string& field, const std::string& why) {
  throw HttpError(403, "href-not-allowed", field + ": " + why);
}

bool HasDotDot(const std::string& href) {
  for (const auto& part : fs::path(href))
    if (part == "..") return true;
  return false;
}

bool IsUnder(const fs::path& path, const fs::path& root) {
  auto r = root.begin(), p = path.begin();
  for (; r != root.end(); ++r, ++p) {
    if (r->empty()) continue;  // trailing separator
    if (p == path.end() || *p != *r) return false;
  }
  return true;
}

std::string Resolve(const std::string& href, const std::string& field, const InputPolicy& policy,
                    bool directory_ok = false) {
  if (href.find('\0') != std::string::npos) Forbidden(field, "contains a NUL byte");
  if (HasDotDot(href)) Forbidden(field, "'..' is not allowed in hrefs");
  if (href.rfind("/vsi", 0) == 0) {
    for (const auto& prefix : policy.allowed_vsi)
      if (href.rfind(prefix, 0) == 0) return href;
    Forbidden(field, "GDAL virtual path '" + href + "' is not allowed by this server");
  }
  if (policy.data_roots.empty()) Forbidden(field, "this server has no data roots for file inputs");
  const fs::path given(href);
  const fs::path joined = given.is_absolute() ? given : fs::path(policy.data_roots.front()) / given;
  std::error_code ec;
  if (!fs::exists(joined, ec))
    ThrowError(ErrorCode::kInvalidArgument, field + ": '" + href + "' does not exist");
  const fs::path real = fs::canonical(joined, ec);  // resolves every symlink
  if (ec) ThrowError(ErrorCode::kInvalidArgument, field + ": '" + href + "' cannot be resolved");
  for (const auto& root : policy.data_roots) {
    const fs::path real_root = fs::canonical(root, ec);
    if (!ec && IsUnder(real, real_root)) {
      if (directory_ok && fs::is_directory(real)) return real.string();
      if (!fs::is_regular_file(real)) ThrowError(ErrorCode::kInvalidArgument, field + ": '" + href + "' is not a file");
      return real.string();
    }
  }
  Forbidden(field, "'" + href + "' is outside the server's data roots");
}

}  // namespace

std::string InputPolicy::Check() const {
  for (const auto& root : data_roots)
    if (!fs::is_directory(root)) return "data root '" + root + "' is not a directory";
  for (const auto& prefix : allowed_vsi)
    if (prefix.rfind("/vsi", 0) != 0) return "allowed virtual path '" + prefix + "' does not start with /vsi";
  if (max_images < 2) return "max_images: must be >= 2";
  if (max_tiles < 1) return "max_tiles: must be >= 1";
  if (max_pixels < 1) return "max_pixels: must be >= 1";
  if (max_mesh_faces < 1 || max_mesh_faces > JobInitialMesh{}.max_faces)
    return "max_mesh_faces: must be in [1, " + std::to_string(JobInitialMesh{}.max_faces) + "]";
  return "";
}

void ResolveHrefs(nlohmann::json* job, const InputPolicy& policy) {
  if (!job->is_object()) return;
  if (job->contains("images") && (*job)["images"].is_array()) {
    auto& images = (*job)["images"];
    for (size_t i = 0; i < images.size(); ++i) {
      auto& image = images[i];
      if (image.is_object() && image.contains("href") && image["href"].is_string() &&
          !image["href"].get<std::string>().empty())
        image["href"] = Resolve(image["href"], "images[" + std::to_string(i) + "].href", policy);
    }
  }
  if (job->contains("initial") && (*job)["initial"].is_object()) {
    auto& initial = (*job)["initial"];
    if (initial.contains("dsm") && initial["dsm"].is_string() && !initial["dsm"].get<std::string>().empty())
      initial["dsm"] = Resolve(initial["dsm"], "initial.dsm", policy);
    // A previous result (its directory or tileset.json) means its mesh.ply: resolved as
    // that file, so a link inside the directory cannot lead out of the roots.
    if (initial.contains("mesh") && initial["mesh"].is_string() && !initial["mesh"].get<std::string>().empty()) {
      const std::string href = initial["mesh"];
      const std::string real = Resolve(href, "initial.mesh", policy, /*directory_ok=*/true);
      fs::path file(real);
      if (fs::is_directory(file)) file /= "mesh.ply";
      else if (file.filename() == "tileset.json") file = file.parent_path() / "mesh.ply";
      initial["mesh"] = file == fs::path(real) ? real : Resolve(file.string(), "initial.mesh", policy);
    }
  }
}

void CheckLimits(const JobSpec& spec, const ExecutionPlan& plan, const InputPolicy& policy) {
  if (int(spec.images.size()) > policy.max_images)
    ThrowError(ErrorCode::kInvalidArgument, "images: " + std::to_string(spec.images.size()) +
                                                " images exceed this server's limit of " +
                                                std::to_string(policy.max_images));
  if (int(plan.tiles.size()) > policy.max_tiles)
    ThrowError(ErrorCode::kInvalidArgument, "job: " + std::to_string(plan.tiles.size()) +
                                                " tiles exceed this server's limit of " +
                                                std::to_string(policy.max_tiles));
  if (plan.pixels > policy.max_pixels)
    ThrowError(ErrorCode::kInvalidArgument, "images: " + std::to_string(plan.pixels) +
                                                " pixels exceed this server's limit of " +
                                                std::to_string(policy.max_pixels));
}

}  // namespace satmesh::server
