#pragma once
// Per-view quantities that the refinement and the bias estimation both derive from the
// RFM and the options: a view's GSD, its pair-selection inputs, the photometric options
// of a level.
#include "core/geo/local_frame.h"
#include "core/image/image.h"
#include "core/refine/pairs.h"
#include "core/refine/refine.h"
#include "core/refine/photometric_gradient.h"
#include "core/refine/refine_options.h"
#include "core/rpc/rpc_model.h"

#include <vector>

namespace satmesh {

// Full-resolution ground sampling distance of a view at the frame centre, metres.
double GroundSamplingDistance(const RpcModel& rpc, const LocalFrame& frame);

// Contrast (std) of the view's normalised image, its central viewing direction (virtual
// camera between frame heights min_z-1 and max_z+1) and its window's ground footprint at
// the mid height (frame x/y).
PairCandidateView MakePairCandidate(const RpcModel& rpc, const LocalFrame& frame,
                                    const ImageF& normalised, double min_z, double max_z);

// Everything of one view the refinement's steps share, made once: the normalised image's
// pyramid (level 0 = full resolution), the RPC (with the bias estimated so far), the
// pair-selection inputs and the full-resolution GSD.
struct PreparedView {
  std::vector<ImageF> pyramid;
  RpcModel rpc;
  PairCandidateView candidate;
  double gsd_m = 0;
  std::vector<double> noise_variance;  // per pyramid level: NoiseSigma² at full resolution / 4^level
};

// Radiometric normalisation, pyramids of levels + 1 images, candidates (acquisition
// metadata from each view's `acquisition`).
std::vector<PreparedView> PrepareViews(const RefineInput& input, int levels);

// SelectPairs over the prepared views, the surface being the initial mesh's extent.
PairSelection SelectViewPairs(const RefineInput& input, const std::vector<PreparedView>& views,
                              const PairOptions& options);

// The photometric options of a level whose GSD is gsd_m and whose images' noise variance
// is noise_variance (the ZNCC's variance floor: options.variance_floor, raised to
// options.noise_variance_factor x the noise variance).
PhotometricOptions PhotometricOptionsAt(const RefineOptions& options, double gsd_m,
                                        double noise_variance = 0);

// Mean noise variance of the views at `level`.
double MeanNoiseVariance(const std::vector<PreparedView>& views, int level);

}  // namespace satmesh
