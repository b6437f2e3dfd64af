#pragma once
// A 2.5D DSM degraded the way stereo pipelines err: edge fattening (foreground dilated
// into the background), blur, spatially correlated and white noise, blob outliers and
// NaN holes. The starting surface of the synthetic benchmarks.
#include <cstdint>
#include <string>

#include "core/dsm/dsm.h"

namespace satmesh::synth {

struct DegradeOptions {
  double fattening_m = 0.9;          // foreground dilation radius at height steps, m, >= 0
  double blur_sigma_m = 0.6;         // Gaussian blur, m, >= 0
  double noise_sigma_m = 0.35;       // spatially correlated noise, m, >= 0
  double noise_correlation_m = 1.5;  // its correlation length (Gaussian sigma), m, > 0
  double white_noise_m = 0.12;       // per-cell noise, m, >= 0
  double blobs_per_hectare = 8;      // smooth bumps/dents, >= 0
  double blob_height_m = 2.5;        // their largest |amplitude|, m, >= 0
  double holes_per_hectare = 6;      // NaN holes, >= 0
  double hole_radius_m = 4;          // their typical radius, m, > 0
  std::string Check() const;
};

// Same grid as `truth`; NaN truth cells are filled from their neighbourhood first.
// Throws Error{kInvalidArgument} on invalid options or an empty grid.
Dsm DegradeDsm(const Dsm& truth, const DegradeOptions& options, uint64_t seed);

}  // namespace satmesh::synth
