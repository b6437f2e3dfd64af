#pragma once
// Per-view quantities that the refinement and the bias estimation both derive from the
// RFM and the options: a view's GSD, its pair-selection inputs, the photometric options
// of a level.
#include "core/geo/local_frame.h"
#include "core/image/image.h"
#include "core/refine/pairs.h"
#include "core/refine/photometric_gradient.h"
#include "core/refine/refine_options.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

// Full-resolution ground sampling distance of a view at the frame centre, metres.
double GroundSamplingDistance(const RpcModel& rpc, const LocalFrame& frame);

// Contrast (std) of the view's normalised image and its central viewing direction
// (virtual camera between frame heights min_z-1 and max_z+1).
PairCandidateView MakePairCandidate(const RpcModel& rpc, const LocalFrame& frame,
                                    const ImageF& normalised, double min_z, double max_z);

// The photometric options of a level whose GSD is gsd_m.
PhotometricOptions PhotometricOptionsAt(const RefineOptions& options, double gsd_m);

}  // namespace satmesh
