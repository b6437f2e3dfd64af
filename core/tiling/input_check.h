#pragma once
// A planned job's input files checked before any tile runs, so that bad data is refused
// at submission (server) or before the first tile (CLI) with one message naming the
// job's field, the file and the value, instead of a tile failing later (or a result made
// from the wrong data). What is checked, in order:
//   initial.dsm   heights in metres (band unit, vertical CRS), not all nodata in the AOI
//   images[i]     opens as a raster, its last block is readable (a truncated file), at
//                 least kMinImageSidePx on each side, has an RPC, is not the same file or
//                 the same image (same RPC and size) as an earlier one, its RPC's ground
//                 domain holds the AOI (else: an image of another place), and the AOI
//                 projects into its pixels (else: RPCs that miss the image)
// The DSM's CRS itself (projected, metres) is checked by PlanJob.
#include <string>

#include "core/tiling/job_spec.h"
#include "core/tiling/tile_plan.h"

namespace satmesh {

constexpr int kMinImageSidePx = 16;  // smaller images cannot hold one ZNCC window per level

// Throws Error{kInvalidInput} (Error{kNotFound} for a missing file) whose message starts
// with the job's field ("images[2].href: ..." or "initial.dsm: ...") and names the file.
void CheckJobInputs(const JobSpec& spec, const JobPlan& plan);

}  // namespace satmesh
