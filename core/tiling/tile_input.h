#pragma once
// Per-tile inputs: the local frame at the tile centre, the initial surface as a mesh in
// that frame, and for every image the pixel window that sees the tile's 3D box, read
// through GDAL, with its RPC cropped to the window.
#include <string>
#include <vector>

#include "core/dsm/dsm.h"
#include "core/refine/refine.h"
#include "core/tiling/job.h"

namespace satmesh {

struct TileInput {
  RefineInput refine;
  std::string dsm_crs_wkt;   // CRS of the initial DSM
  std::vector<std::string> view_names;
};

// Downsamples a DSM by an integer factor (NaN-aware block mean; a block with no valid
// cell stays NaN).
Dsm DownsampleDsm(const Dsm& dsm, int factor);

// Builds the refinement input for the whole initial DSM. coarse_cell_m: cell size of the
// initial mesh (the refinement remeshes it to its coarse level anyway).
TileInput PrepareTileInput(const JobSpec& spec, const Dsm& initial_dsm, double coarse_cell_m);

}  // namespace satmesh
