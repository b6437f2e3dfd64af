#pragma once
// Filling a DSM's holes before it becomes the initial surface. Stereo DSMs (s2p, ASP,
// SGM) leave cells empty where matching failed: occlusions beside walls, shadows, water,
// and single cells between rasterised points (42% of the Pléiades triplet's s2p DSM is
// empty, most of it outside the images' footprint). Meshed as they are, these holes stay
// holes in the refined mesh: the refinement moves vertices, it does not create surface.
#include "core/dsm/dsm.h"

namespace satmesh {

// Fills the empty (NaN) cells of `dsm` inside the convex hull of its valid cells by
// GDAL's inverse-distance interpolation (GDALFillNodata) from the valid cells within
// max_distance_m; cells farther from any valid cell, and every cell outside the hull
// (off the data's footprint), stay empty. max_distance_m <= 0 fills nothing. Returns the
// number of cells filled. Writes no file: GDAL's work rasters stay in memory.
size_t FillDsmHoles(Dsm* dsm, double max_distance_m);

}  // namespace satmesh
