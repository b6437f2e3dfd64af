#pragma once
// Assembly of the tiles' files into the job's outputs, the seam measurement and the
// 3D Tiles tileset (as a core struct; proto/ writes it as tileset.json).
#include <array>
#include <string>
#include <vector>

#include "core/tiling/job_spec.h"
#include "core/tiling/tile_plan.h"
#include "core/tiling/tile_run.h"

namespace satmesh {

// Height difference of two neighbouring tiles' refined surfaces along their shared core
// edge: both tiles refined the cells on either side of it (overlap), so |z_a - z_b| there
// is the step the trimmed pieces leave in the assembled outputs.
struct SeamStats {
  std::string a, b;             // tile names; b is east or north of a
  int cells = 0;                // cells where both tiles have a surface
  double median_abs_m = 0, p95_abs_m = 0, max_abs_m = 0;
  double mean_m = 0;            // mean z_a - z_b (a systematic offset)
};

struct TilesetTile {
  std::string name, uri;                 // uri relative to tileset.json
  std::array<double, 6> region{};        // west, south, east, north (rad), min h, max h (m)
  std::array<double, 16> transform{};    // column-major, tile frame (z-up ENU) -> ECEF
  double geometric_error = 0;            // m
};

struct Tileset {                         // 3D Tiles 1.1: a root (no content) + leaves
  std::array<double, 6> region{};        // union of the leaves'
  double geometric_error = 0;            // m (root and tileset)
  std::vector<TilesetTile> tiles;
};

struct Assembly {
  std::string mesh_path, dsm_path;       // out_dir/mesh.ply, out_dir/dsm.tif
  std::string confidence_path;           // out_dir/confidence.tif (tile_run.h,
                                         // ConfidenceFromHeightSigma); empty: not written
  size_t vertices = 0, faces = 0;        // of the assembled mesh
  int tiles_ok = 0, tiles_failed = 0;
  std::vector<SeamStats> seams;          // one per pair of neighbouring successful tiles
  SeamStats seams_total;                 // over every seam cell
  Tileset tileset;
  double assemble_s = 0;
};

Tileset BuildTileset(const JobPlan& plan, const std::vector<TileResult>& results);

// Reads the successful tiles' files: concatenates their core pieces into mesh.ply (output
// CRS, double), fills dsm.tif (the AOI's cells on the initial DSM's grid; failed tiles'
// cells stay nodata) from their refined DSMs' core cells, measures the seams and builds
// the tileset. Holds the assembled outputs plus two tiles' DSMs at a time. Throws
// Error{kInvalidInput} naming the first reason when no tile succeeded.
Assembly AssembleOutputs(const JobPlan& plan, const std::vector<TileResult>& results,
                         const std::string& out_dir);

}  // namespace satmesh
