#pragma once
// AOI -> square tiles with overlap on the job's grid: the initial DSM's (reads only its
// header), or for a job from a mesh alone a grid over the mesh's extent.
#include <Eigen/Core>
#include <array>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/dsm/dsm.h"
#include "core/image/image_io.h"
#include "core/tiling/job_spec.h"

namespace satmesh {

struct InitialMesh;  // initial_mesh.h

// An axis-aligned box in the plan's CRS (the initial DSM's).
struct Box2d {
  double xmin = 0, ymin = 0, xmax = 0, ymax = 0;
  bool Contains(double x, double y) const { return x >= xmin && x <= xmax && y >= ymin && y <= ymax; }
  double width() const { return xmax - xmin; }
  double height() const { return ymax - ymin; }
};

// The initial DSM's grid without its heights.
struct DsmGrid {
  int width = 0, height = 0;
  std::array<double, 6> geo_transform{0, 1, 0, 0, 0, -1};  // north-up
  std::string crs_wkt;
  // The box covered by a window of cells.
  Box2d BoxOf(const PixelWindow& cells) const;
};

// Peak resident memory of refining one tile, estimated before it starts (memory_budget.h).
struct TileMemoryEstimate {
  int views = 0;             // images whose window sees the tile
  double window_px = 0;      // their full-resolution window pixels, summed
  double dsm_cells = 0;      // initial DSM cells of the padded tile
  double peak_mb = 0;        // estimated process peak while refining it (MB = 2^20 bytes)
};

struct PlannedTile {
  int x = 0, y = 0;            // column (west -> east) and row (south -> north) of the grid
  PixelWindow core_cells;      // DSM cells kept after trimming (cell centres inside core)
  PixelWindow padded_cells;    // core + overlap, clipped to the DSM: what is refined
  Box2d core, padded;          // the same windows as boxes in the DSM's CRS
  TileMemoryEstimate memory;   // its refinement's estimated peak
  std::string Name() const { return std::to_string(x) + "_" + std::to_string(y); }
};

struct JobPlan {
  DsmGrid dsm;                   // every extent is in dsm.crs_wkt
  std::string output_crs;        // resolved: spec.output_crs or the DSM's CRS
  std::vector<Eigen::Vector2d> aoi_polygon;  // in the DSM's CRS
  PixelWindow aoi_cells;         // the AOI's bounding cells (grid of the assembled DSM)
  int tile_cells = 0, overlap_cells = 0;  // tile core edge and overlap, in cells
  int nx = 0, ny = 0;            // tile grid size
  std::vector<PlannedTile> tiles;  // tiles meeting the AOI, row by row from the south-west
  double memory_budget_mb = 0;   // one worker's budget (MemoryBudgetMb of the spec's tiling)
  bool auto_tiled = false;       // tiling.size_m was 0 and one tile would not fit the budget
  // Mesh jobs: the initial mesh's lowest and highest point in dsm.crs_wkt (NaN otherwise).
  double mesh_zmin = std::numeric_limits<double>::quiet_NaN();
  double mesh_zmax = std::numeric_limits<double>::quiet_NaN();
  // Mesh jobs: the initial mesh in dsm.crs_wkt, repaired and its holes filled
  // (InitialMeshIn), made once by PlanJob and clipped by each tile (null: a tile makes it).
  std::shared_ptr<const InitialMesh> initial_mesh;
  int IndexOf(int x, int y) const;  // -1 when (x, y) was not planned
};

// Reads the DSM header, maps the AOI into its CRS (edges densified) and cuts the AOI's
// bounding cells into tiles of round(tile_size_m / cell) cells (the last row/column
// takes the remainder, between half and one and a half tiles), keeping those whose core
// meets the AOI polygon. Estimates each tile's peak memory (reads the images' RPCs and
// the DSM, no pixels). tile_size_m = 0 gives one tile over the AOI if it fits the memory
// budget, else the largest square tiles that do; Error{kInvalidArgument} naming budget
// and need when even a tile of 2 overlaps (at least 32 cells) would not fit. Throws Error{kInvalidArgument} naming the field for a bad spec,
// Error{kInvalidInput} for a geographic or rotated DSM or an AOI outside it.
// Mesh jobs (spec.initial_mesh; initial_mesh.h): the grid is the mesh's extent in the
// planning CRS (MeshPlanCrs) at spec.dsm_resolution_m (0: the images' median GSD at the
// mesh's centre), unless a DSM gives it; a bad mesh, one outside the AOI or outside the
// images' footprint (no image sees its bounding box within the RPC's height range: a
// wrong CRS) throws Error{kInvalidArgument} naming the file and the problem.
JobPlan PlanJob(const JobSpec& spec);

// Reads a window of cells of a DSM (nodata -> NaN); cells outside the raster are NaN.
Dsm ReadDsmWindow(const std::string& path, const PixelWindow& cells);
DsmGrid ReadDsmGrid(const std::string& path);

}  // namespace satmesh
