#pragma once
// How strongly the images constrain each vertex of the refined surface, and from it the
// weight of the thin-plate term per vertex (refine.cc's update divides beta by it):
// where the images say little (no texture, shadow, one narrow pair, occlusion), the
// surface stays smooth and near where it started instead of following matching noise.
#include <vector>

#include "core/refine/pairs.h"
#include "core/refine/refine.h"
#include "core/refine/refine_options.h"

namespace satmesh {

// Height information of a pair: (B/H)², B/H = 2 tan(angle / 2) (the inverse variance of a
// height from one pixel of disparity, in units of GSD⁻²).
double PairHeightInformation(double angle_deg);

// From the pairs' geometry only (height_sigma_gsd 0): the pairs that see a vertex,
// `relative_information` = their PairHeightInformation over one pair at the optimal
// angle, clamped to [min_height_confidence, 1].
double HeightConfidence(double relative_information, const RefineOptions& options);

// Mean over the pairs of PairHeightInformation, relative to one pair at the optimal angle.
double MeanRelativePairInformation(const std::vector<StereoPair>& pairs,
                                   const RefineOptions& options);

// Per vertex, sqrt(noise_variance / information) in metres: how well the images determine
// its position along the normal (1 sigma under their noise); +inf where no pixel saw it.
std::vector<float> HeightSigmaFromInformation(const std::vector<double>& information,
                                              double noise_variance);

// The initial surface as a prior (the "never worse than the input"): per vertex,
// the share of its move that goes back towards where it started at the coarsest level,
// sigma_img² / (sigma_img² + prior_sigma_m²), sigma_img² = noise_variance / information:
// the weight of the initial surface in the product of two Gaussians, the images' height
// estimate (sigma_img) and the initial surface (prior_sigma_m). 1 where no pixel sees the
// vertex, -> 0 where the images pin it.
std::vector<float> InitialPriorWeights(const std::vector<double>& information,
                                       double noise_variance, double prior_sigma_m);

// From the images (height_sigma_gsd > 0): `information` per vertex is the Fisher
// information Σ w_k² (∂b/∂n)² of the pixels that see it (GradientAccumulator::
// AddInformation), so its height is known to sigma = sqrt(noise_variance / I).
// Confidence 1 where sigma <= height_sigma_gsd x gsd_m, else (target / sigma)², floored at
// min_height_confidence. Fills stats->height_sigma_gsd_q (10/50/90% of sigma in GSD).
std::vector<float> HeightConfidenceFromInformation(const std::vector<double>& information,
                                                   double noise_variance, double gsd_m,
                                                   const RefineOptions& options,
                                                   LevelStats* stats);

}  // namespace satmesh
