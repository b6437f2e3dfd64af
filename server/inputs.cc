#include "server/inputs.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/common/error.h"
#include "core/image/image_io.h"
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

// A remote server may decode %2e%2e/%2f into a path outside the allowed prefix.
bool HasEncodedSeparator(const std::string& href) {
  std::string lower = href;
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  return href.find('\\') != std::string::npos || lower.find("%2e") != std::string::npos ||
         lower.find("%2f") != std::string::npos || lower.find("%5c") != std::string::npos;
}

// The file must be a self-contained raster format: a VRT (or WMS, ...) under a data root
// would make GDAL read files or URLs named inside it.
std::string CheckDriver(const std::string& path, const std::string& href, const std::string& field) {
  const std::string driver = RasterDriverName(path);
  if (driver.empty()) return path;  // not a raster GDAL knows: the input checks name it
  for (const char* allowed : kInputRasterDrivers)
    if (driver == allowed) return path;
  Forbidden(field, "'" + href + "' is a " + driver +
                       " file; inputs must be a self-contained raster format (GTiff, COG, NITF, "
                       "JP2OpenJPEG, PNG, JPEG, HFA), not one that references other files or URLs");
}

std::string Resolve(const std::string& href, const std::string& field, const InputPolicy& policy,
                    bool directory_ok = false) {
  if (href.find('\0') != std::string::npos) Forbidden(field, "contains a NUL byte");
  if (HasDotDot(href)) Forbidden(field, "'..' is not allowed in hrefs");
  if (href.rfind("/vsi", 0) == 0) {
    for (const auto& prefix : policy.allowed_vsi) {
      if (href.rfind(prefix, 0) != 0) continue;
      if (HasEncodedSeparator(href.substr(prefix.size())))
        Forbidden(field, "'" + href + "': encoded dots, slashes or backslashes are not allowed in virtual paths");
      return CheckDriver(href, href, field);
    }
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
      return CheckDriver(real.string(), href, field);
    }
  }
  Forbidden(field, "'" + href + "' is outside the server's data roots");
}

}  // namespace

std::string InputPolicy::Check() const {
  for (const auto& root : data_roots)
    if (!fs::is_directory(root)) return "data root '" + root + "' is not a directory";
  for (const auto& prefix : allowed_vsi)
    if (prefix.rfind("/vsi", 0) != 0 || prefix.back() != '/')
      return "allowed virtual path '" + prefix + "' must start with /vsi and end with '/' (else "
             "'/vsicurl/https://host' would also allow https://host.evil.example)";
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

void CheckImageCount(size_t images, const InputPolicy& policy) {
  if (images > size_t(std::max(0, policy.max_images)))
    ThrowError(ErrorCode::kInvalidArgument, "images: " + std::to_string(images) +
                                                " images exceed this server's limit of " +
                                                std::to_string(policy.max_images));
}

void CheckLimits(const JobSpec& spec, const ExecutionPlan& plan, const InputPolicy& policy) {
  CheckImageCount(spec.images.size(), policy);
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
