#pragma once
// What a job may reference and how much it may ask for: hrefs only under the operator's
// data roots (no "..", no symlink escapes) or GDAL virtual paths the operator allows,
// and limits on images, tiles and pixels per job.
#include <nlohmann/json.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "server/executor.h"

namespace satmesh::server {

struct InputPolicy {
  std::vector<std::string> data_roots;  // directories inputs may come from; relative hrefs resolve against the first
  std::vector<std::string> allowed_vsi; // GDAL virtual path prefixes allowed, e.g. "/vsicurl/"; empty = none
  int max_images = 64;                  // images per job, >= 2
  int max_tiles = 1024;                 // tiles per job, >= 1
  int64_t max_pixels = 4'000'000'000;   // total image pixels per job, >= 1
  size_t max_mesh_faces = 20'000'000;   // faces of a job's initial mesh, in [1, the core's
                                        // JobInitialMesh::max_faces]
  std::string Check() const;
};

// GDAL drivers an input may be opened with: self-contained raster formats (no VRT, WMS
// or other format that makes GDAL read further files or URLs named inside the file).
inline constexpr const char* kInputRasterDrivers[] = {"GTiff", "COG", "NITF", "JP2OpenJPEG", "PNG", "JPEG", "HFA"};

// Rewrites every href of the job (images[i].href, initial.dsm, initial.mesh) to an
// absolute, resolved path; an initial.mesh naming a previous result (its directory or
// tileset.json) becomes that result's mesh.ply (core/tiling/initial_mesh.h). Throws HttpError 403 for a path outside the roots (or a virtual path not allowed)
// and Error{kInvalidArgument} naming the field for a file that does not exist. Fields of
// the wrong shape are left for the job parser to name.
// Refused with 403 (RELIABILITY.md, "Paths from requests"): NUL bytes; ".." components;
// symlinks and absolute paths leading outside the roots; /vsi prefixes not allowed; in
// an allowed virtual path, URL-encoded dots, slashes or backslashes (%2e, %2f, %5c) and
// backslashes, which a remote server may decode into a path outside the allowed prefix;
// a file (local or virtual) that GDAL would open with a driver not in kInputRasterDrivers.
void ResolveHrefs(nlohmann::json* job, const InputPolicy& policy);

// Throws Error{kInvalidArgument} when `images` exceed policy.max_images: checked on the
// request before any href is looked up (a job of 500 images costs no file access).
void CheckImageCount(size_t images, const InputPolicy& policy);

// Throws Error{kInvalidArgument} naming the limit a planned job exceeds.
void CheckLimits(const JobSpec& spec, const ExecutionPlan& plan, const InputPolicy& policy);

}  // namespace satmesh::server
