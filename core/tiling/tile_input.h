#pragma once
// Per-tile inputs: the local frame at the tile centre, the initial surface cropped to the
// tile (+ overlap) as a mesh in that frame, and for every image that sees the tile's 3D
// box the pixel window, read through GDAL, with its RPC cropped to the window.
#include <string>
#include <vector>

#include "core/dsm/dsm.h"
#include "core/image/image_io.h"
#include "core/refine/refine.h"
#include "core/rpc/rpc_model.h"
#include "core/tiling/job_spec.h"
#include "core/tiling/tile_plan.h"

namespace satmesh {

struct TileInput {
  RefineInput refine;
  std::string dsm_crs_wkt;   // CRS of the initial DSM
  std::vector<std::string> view_names;
  std::vector<std::string> dropped_views;  // images that do not see the tile
  double image_bytes = 0;    // full-resolution image windows held, bytes
  size_t filled_dsm_cells = 0;  // the DSM's empty cells filled before meshing (FillDsmHoles);
                                // mesh jobs with a DSM: its cells added where the mesh has none
  Dsm initial_heights;       // the initial surface's height per cell of the tile (NaN: none)
};

// The job grid's cells `cells` as an empty (NaN) DSM.
Dsm TileGrid(const JobPlan& plan, const PixelWindow& cells);

// The pixel window of `rpc` that sees the points `box_geo` (geodetic corners of a 3D box),
// widened by margin_px and clipped to the raster.
PixelWindow ImageWindowSeeing(const RpcModel& rpc, const std::vector<Eigen::Vector3d>& box_geo,
                              const RasterInfo& info, int margin_px);

// Window margin for the coarsest level's pixels (the GSD is not known before the images
// are read: the DSM's cell stands in for it, as in CoarseCellSize); initial_is_mesh: the
// job starts from a mesh (ResolveLevels).
int TileWindowMarginPx(const RefineOptions& options, double cell_m, bool initial_is_mesh);

// A mesh whose absolute vertices are in `crs` (origin added), in `frame` (no origin, no CRS).
// Taken by value: a temporary (a tile's DSM mesh) is moved in, not copied. `crs` must not
// be the moved mesh's own string.
TriangleMesh MeshInFrame(TriangleMesh mesh, const std::string& crs, const LocalFrame& frame);

// Downsamples a DSM by an integer factor (NaN-aware block mean; a block with no valid
// cell stays NaN).
Dsm DownsampleDsm(const Dsm& dsm, int factor);

// Cell size of the initial mesh: half the coarse level's triangle edge (the refinement
// remeshes it to its coarse level anyway).
double CoarseCellSize(const RefineOptions& options, double dsm_cell_m);

// The cell the initial mesh of `dsm` is made at: its own where the user trusts it
// (options.trusted_initial) or its heights' noise at one cell (DsmCellNoise) is at most
// options.sharp_dsm_noise_cells (> 0) cells, else
// coarse_cell_m (CoarseCellSize; its block averages halve a noisy DSM's noise and round a
// sharp one's walls off). Synthetic 0.5 m stereo / tri-stereo / narrow stereo from a DSM
// whose walls are in place (noise 0.06 cell): facades @0.5 m 34.8 / 36.2 / 35.2% averaged,
// 46.9 / 46.4 / 46.5% at full resolution (the DSM's own 46.2%), roofs equal. From a sharp
// DSM whose walls a stereo pipeline fattened by 0.9 m (`synth --initial-dsm sharp`, 0.12
// cell): 16.8 / 19.9 / 18.8% averaged, 6.0 / 7.8 / 7.1% at full resolution, F 5 points
// lower: the images move a blurred wall, not a sharp one. The Pléiades s2p DSM (0.10
// cell): held-out narrow pairs -0.0040 / -0.0035 averaged, -0.0038 / -0.0035 at full
// resolution (docs/benchmarks-history.md, session 30). `noise_m`: the noise (always
// measured, for the log).
double InitialMeshCell(const RefineOptions& options, const Dsm& dsm, double coarse_cell_m,
                       double* noise_m = nullptr);

// Builds the refinement input over all of `initial_dsm` (its centre is the frame's), after
// filling its holes up to spec.fill_holes_m from data (FillDsmHoles).
TileInput PrepareTileInput(const JobSpec& spec, Dsm initial_dsm, double coarse_cell_m);

// The same for one planned tile: reads only the DSM cells of the padded tile and only
// the image windows that see its 3D box (extent x height range +- margin). Mesh jobs
// (spec.initial_mesh): the initial mesh clipped to the padded box (ClipInitialMesh: 3D
// kept, nothing rasterised), the DSM, if given too, added where the mesh has no surface;
// the frame at the box centre, the height range from the piece. Throws
// Error{kInvalidInput} when the tile has no valid DSM cell / no mesh surface.
TileInput PrepareTileInput(const JobSpec& spec, const JobPlan& plan, int tile_index);

}  // namespace satmesh
