#pragma once
// One tile: prepare its input, refine, trim to its core, write its files. Independent of
// every other tile, so a worker pool (in-process or the server's) can run tiles in any
// order, again, or on another machine.
#include <array>
#include <string>
#include <vector>

#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/refine/refine.h"
#include "core/tiling/job_spec.h"
#include "core/tiling/tile_plan.h"

namespace satmesh {

struct TileResult {
  int index = -1;
  std::string name;                 // "<x>_<y>"
  bool ok = false;
  ErrorCode error_code = ErrorCode::kInternal;  // when !ok
  std::string error;                // when !ok: why the tile failed
  std::vector<std::string> view_names, dropped_views;
  RefineResult refine;              // stats; mesh kept only when asked (keep_mesh)
  size_t core_vertices = 0, core_faces = 0;   // the trimmed piece
  // 3D Tiles: region [west, south, east, north] (radians, WGS84) + [min h, max h] (m) of
  // the piece, and the column-major 4x4 transform from the .glb's frame (glTF y-up, ENU
  // at the core centre: x east, y up, z south) to ECEF... as 3D Tiles expects it: the
  // tile transform maps the z-up ENU frame to ECEF, glTF's y-up is rotated by the viewer.
  std::array<double, 6> region{};
  std::array<double, 16> transform{};
  double image_mb = 0;              // image windows held while refining (full resolution)
  double peak_rss_mb = 0;           // process peak resident memory after the tile
  double prepare_s = 0, refine_s = 0, write_s = 0;
};

// Files of a tile under out_dir/tiles/ (relative to out_dir).
std::string TileGlbPath(const PlannedTile& tile);    // tiles/<x>_<y>.glb: core, Draco glTF
std::string TilePiecePath(const PlannedTile& tile);  // tiles/<x>_<y>.ply: core, output CRS
std::string TileDsmPath(const PlannedTile& tile);    // tiles/<x>_<y>.tif: padded, DSM grid

// Refines tile `tile_index` of `plan` and writes its files (each written to a temporary
// name and renamed, so re-running a tile is safe and gives the same files). Never throws
// for a tile that fails (reason in the result) except Error{kCancelled}.
TileResult RunTile(const JobSpec& spec, const JobPlan& plan, int tile_index,
                   const std::string& out_dir, const Progress& progress = {},
                   bool keep_mesh = false);

// The part of a mesh inside `box` (x, y; any z): faces crossing the box's edges are cut
// exactly along them (Sutherland-Hodgman; a cut edge shared by two faces gives one
// vertex), so neighbouring tiles' pieces meet along the edge without gap or overlap.
struct PointMesh {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> faces;
};
PointMesh ClipToBox(const PointMesh& mesh, const Box2d& box);

}  // namespace satmesh
