#pragma once
// 2.5D metrics of a DSM against a reference DSM (the paper's 4.3): residuals
// r = result - truth on a mask, completeness, RMSE, NMAD, perc-68, MAE; and an
// XY shift + Z offset alignment in the manner of JHU/APL's align3d.
#include <cstdint>
#include <string>
#include <vector>

#include "core/dsm/dsm.h"

namespace satmesh {

// Statistics of one residual set. Fractions are of all evaluated cells (a NaN residual,
// i.e. a hole in the result, counts as incomplete); the other statistics use the finite
// residuals (RMSE only those with |r| < the completeness threshold).
struct DsmMetrics {
  size_t num_cells = 0;           // cells evaluated (mask cells with a finite truth)
  size_t num_valid = 0;           // of those, with a finite result
  double completeness = 0;        // fraction with |r| < 3 m (DsmMetricsOptions)
  double completeness_1m = 0;     // fraction with |r| < 1 m
  double completeness_05m = 0;    // fraction with |r| < 0.5 m
  double rmse_m = 0;              // sqrt(mean r^2) over |r| < 3 m
  double nmad_m = 0;              // 1.4826 * median(|r - median(r)|)
  double perc68_m = 0;            // 68th percentile of |r|
  double mae_m = 0;               // mean |r|
  double median_m = 0;            // median r (signed)
};

struct DsmMetricsOptions {
  double completeness_threshold_m = 3.0;  // |r| below counts as complete (and enters RMSE), > 0
  std::string Check() const;
};

// Metrics of residuals (NaN = missing result). Empty input gives all zeros.
DsmMetrics ComputeDsmMetrics(const std::vector<float>& residuals_m,
                             const DsmMetricsOptions& options = {});

// Translation to add to the result to bring it onto the truth.
struct Alignment {
  double dx_m = 0, dy_m = 0, dz_m = 0;
  int shift_i = 0, shift_j = 0;  // the XY shift in cells: result cell (i - shift_i, j - shift_j)
                                 // is compared with truth cell (i, j)
};

struct AlignOptions {
  double max_shift_m = 3.0;      // XY search half-width (align3d's maxt), >= 0
  size_t max_cells = 200000;     // cells used per candidate shift (regular subsample), >= 100
  double robust_clip_m = 3.0;    // |r - dz| is clipped here in the score, > 0
  std::string Check() const;
};

// Search over integer cell shifts within +-max_shift_m, coarse to fine (every s-th shift,
// s = max shift in cells / 4, on a quarter of the cells; then +-s around the best on all
// used cells). Per shift, dz = median of the residuals and the score =
// mean(min(|r - dz|, clip)); the lowest score wins (ties: the smaller shift).
// mask: empty = all cells, else one byte per cell (non-zero = use). Grids must match.
Alignment AlignDsm(const Dsm& result, const Dsm& truth, const std::vector<uint8_t>& mask,
                   const AlignOptions& options = {});

// Residuals result - truth (shifted by `alignment`) on the mask cells with a finite truth.
std::vector<float> DsmResiduals(const Dsm& result, const Dsm& truth,
                                const std::vector<uint8_t>& mask, const Alignment& alignment = {});

struct DsmEvalOptions {
  DsmMetricsOptions metrics;
  AlignOptions align;
  bool align_on_mask = false;  // estimate the alignment on the mask cells only (else all)
  std::string Check() const;
};

struct DsmEvaluation {
  DsmMetrics mask_raw, mask_aligned;  // on the mask (e.g. roofs)
  DsmMetrics all_raw, all_aligned;    // on all cells
  Alignment alignment;
};

// Both ways (raw and aligned), on the mask and on all cells. Throws Error if the grids
// (size, transform) or the mask size do not match.
DsmEvaluation EvaluateDsm(const Dsm& result, const Dsm& truth, const std::vector<uint8_t>& mask,
                          const DsmEvalOptions& options = {});

// Mask from a Byte grid read with ReadDsm (value > 0.5 = 1).
std::vector<uint8_t> MaskFromDsm(const Dsm& mask_grid);

}  // namespace satmesh
