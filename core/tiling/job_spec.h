#pragma once
// A refinement job in core terms. No JSON here: proto/ parses the wire format into this.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/refine/refine_options.h"

namespace satmesh {

struct JobImage {
  std::string path;                        // GDAL-readable image with an RPC
  Eigen::Vector2d bias_col_row_px{0, 0};   // RPC bias correction, full-resolution pixels
};

// Area of interest: a polygon (a bbox is its 4 corners) in any CRS. Empty = the initial
// DSM's extent, else the part of the initial mesh's extent two images see (footprints at
// the mesh's mid height).
struct JobAoi {
  std::vector<Eigen::Vector2d> polygon;  // (x, y) in `crs`; >= 3 points, or empty
  std::string crs;                       // "" = the planning CRS (initial DSM's or mesh's)
};

// The job's "tiling"; wire names, ranges and help: TilingOptionTable() (tile_plan.cc).
struct TilingOptions {
  double tile_size_m = 0;   // edge of the square tile cores, DSM CRS units (m); 0 = one tile
  double overlap_m = 24;    // refined beyond each core edge, then trimmed, m
  int workers = 1;          // tiles refined at once in-process
  double memory_budget_mb = 0;  // one worker's peak, MB (2^20 bytes); 0: a quarter of
                                // the machine's memory / workers (memory_budget.h). With
                                // tile_size_m = 0 the AOI is cut into tiles that fit it; a
                                // tile that cannot fit is refused, naming budget and need
  std::string Check() const;  // messages name tiling.<wire name>
};

using TilingOptionInfo = OptionInfo<TilingOptions>;
// Every tiling option, in the schema's order (core/common/option_table.h).
const std::vector<TilingOptionInfo>& TilingOptionTable();

// The initial surface's mesh (core/tiling/initial_mesh.h reads and checks it).
struct JobInitialMesh {
  std::string path;        // PLY, OBJ, .glb/.drc; or a previous job's result directory or
                           // its tileset.json (that job's mesh.ply); "" = none
  std::string crs;         // "" = the file's (PLY/OBJ "crs" comment), else outputs.crs
  size_t max_faces = 20'000'000;  // a larger mesh is refused (not on the wire: a server
                                  // sets its own limit), >= 1
};

struct JobSpec {
  std::vector<JobImage> images;
  // The initial surface: a DSM, a mesh, or both (the mesh is refined; the DSM fills
  // only where the mesh has no surface). At least one.
  std::string initial_dsm;     // GeoTIFF DSM (ellipsoidal heights), projected CRS; "" = none
  JobInitialMesh initial_mesh;
  double fill_holes_m = 50;    // the DSM's holes filled up to this far from data (FillDsmHoles),
                               // a mesh's up to this size across (FillHoles), m; 0: none
  std::string output_crs;      // "" = the initial DSM's CRS, else the initial mesh's
  // Mesh jobs without a DSM: cell of the job's grid (dsm.tif, the tiles' DSMs), m in the
  // planning CRS, >= 0; 0 = the images' GSD. Ignored when initial_dsm gives the grid.
  double dsm_resolution_m = 0;
  JobAoi aoi;
  TilingOptions tiling;
  RefineOptions refine;
  std::string Check() const;   // "" or what is wrong (field named)
  // The job refines a mesh (initial_mesh given), not a DSM.
  bool StartsFromMesh() const { return !initial_mesh.path.empty(); }
};

}  // namespace satmesh
