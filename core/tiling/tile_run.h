#pragma once
// One tile: prepare its input, refine, trim to its core, write its files. Independent of
// every other tile, so a worker pool (in-process or the server's) can run tiles in any
// order, again, or on another machine.
#include <array>
#include <string>
#include <vector>

#include "core/common/error.h"
#include "core/common/progress.h"
#include "core/mesh/mesh_clean.h"
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
  // the piece (padded 0.1 m), and the column-major 4x4 tile transform from the tile frame
  // (z-up ENU at the core centre) to ECEF. The .glb stores glTF y-up positions
  // (east, up, -north), which 3D Tiles viewers rotate into that z-up frame.
  std::array<double, 6> region{};
  std::array<double, 16> transform{};
  double image_mb = 0;              // image windows held while refining (full resolution)
  double peak_rss_mb = 0;           // process peak resident memory after the tile
  double estimated_peak_mb = 0;     // the plan's estimate for the tile (memory_budget.h)
  std::vector<Eigen::Vector2d> view_bias_px;  // estimate_bias: shift added per view (col,
                                              // row; full-res px), in view_names order
  double prepare_s = 0, bias_s = 0, refine_s = 0, write_s = 0;
};

// Files of a tile under out_dir/tiles/ (relative to out_dir).
std::string TileGlbPath(const PlannedTile& tile);    // tiles/<x>_<y>.glb: core, Draco glTF
std::string TilePiecePath(const PlannedTile& tile);  // tiles/<x>_<y>.ply: core, output CRS
std::string TileDsmPath(const PlannedTile& tile);    // tiles/<x>_<y>.tif: padded, DSM grid

// Memory: one tile's image windows (views x (tile + 2 overlap + margins)^2 / GSD^2 x 4 B)
// plus the refinement's per-view workspaces (pyramids, gradients, hit maps; ~30x the
// windows) and the mesh. Measured: 60 m tiles + 12 m overlap, 10 views, 0.3 m GSD: 6 MB
// of windows, 262 MB peak RSS; the same AOI in one piece: 19 MB, 638 MB.
// Refines tile `tile_index` of `plan` and writes its files (each written to a temporary
// name and renamed, so re-running a tile is safe and replaces them). Never throws
// for a tile that fails (reason in the result) except Error{kCancelled}.
TileResult RunTile(const JobSpec& spec, const JobPlan& plan, int tile_index,
                   const std::string& out_dir, const Progress& progress = {},
                   bool keep_mesh = false);

// tiles/NAME.confidence.tif: the padded tile's ConfidenceFromHeightSigma on its DSM grid.
std::string TileConfidencePath(const PlannedTile& t);

// How well the images pin the refined surface, [0, 1]: 1 / (1 + (sigma / GSD)²) for its
// height sigma from the images (TriangleMesh::height_sigma): 1 far below a pixel, 0.5 at
// one GSD, 0 where no image sees it (+inf); NaN stays NaN (no surface).
float ConfidenceFromHeightSigma(float sigma_m, double gsd_m);
Dsm ConfidenceFromHeightSigma(Dsm sigma, double gsd_m);

struct PointMesh {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3i> faces;
  std::vector<float> height_sigma;  // per point, or empty (TriangleMesh::height_sigma)
};

// The part of a mesh inside `box` (x, y; any z): faces crossing the box's edges are cut
// exactly along them (Sutherland-Hodgman; a cut edge shared by two faces gives one
// vertex), so neighbouring tiles' pieces meet along the edge without gap or overlap.
// 3D is kept (walls, overhangs: nothing is projected). The piece is free of debris
// (CleanMesh with `clean`): a cut next to a vertex gives no sliver, three collinear
// points of a cut polygon no zero-area triangle.
PointMesh ClipToBox(const PointMesh& mesh, const Box2d& box, const MeshCleanOptions& clean = {});

// CleanMesh on a PointMesh (through tile-local floats about its centroid, as written).
PointMesh CleanPointMesh(const PointMesh& mesh, const MeshCleanOptions& options = {},
                         MeshDebris* removed = nullptr);

}  // namespace satmesh
