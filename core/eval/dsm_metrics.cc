#include "core/eval/dsm_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/common/error.h"
#include "core/common/stats.h"

namespace satmesh {
namespace {

void CheckSameGrid(const Dsm& a, const Dsm& b, const std::vector<uint8_t>& mask) {
  SATMESH_CHECK(a.width == b.width && a.height == b.height, ErrorCode::kInvalidInput,
                "DSM grids differ in size: result " + std::to_string(a.width) + "x" +
                    std::to_string(a.height) + ", truth " + std::to_string(b.width) + "x" +
                    std::to_string(b.height));
  for (int k = 0; k < 6; ++k) {
    const double tol = 1e-6 * std::max(1.0, std::abs(b.geo_transform[k]));
    SATMESH_CHECK(std::abs(a.geo_transform[k] - b.geo_transform[k]) <= tol,
                  ErrorCode::kInvalidInput,
                  "DSM grids differ in geo_transform[" + std::to_string(k) + "]: " +
                      std::to_string(a.geo_transform[k]) + " vs " +
                      std::to_string(b.geo_transform[k]));
  }
  SATMESH_CHECK(a.z.size() == size_t(a.width) * a.height, ErrorCode::kInvalidInput,
                "result DSM has " + std::to_string(a.z.size()) + " values for its size");
  SATMESH_CHECK(b.z.size() == size_t(b.width) * b.height, ErrorCode::kInvalidInput,
                "truth DSM has " + std::to_string(b.z.size()) + " values for its size");
  SATMESH_CHECK(mask.empty() || mask.size() == b.z.size(), ErrorCode::kInvalidInput,
                "mask has " + std::to_string(mask.size()) + " cells, the DSM " +
                    std::to_string(b.z.size()));
}

// Residuals of the shifted result on the given truth cells (NaN where the result is
// missing or the shift leaves the grid).
void ShiftedResiduals(const Dsm& result, const Dsm& truth, const std::vector<size_t>& cells,
                      int si, int sj, std::vector<float>& out) {
  out.resize(cells.size());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (size_t k = 0; k < cells.size(); ++k) {
    const int i = int(cells[k] % truth.width), j = int(cells[k] / truth.width);
    const int ri = i - si, rj = j - sj;
    if (ri < 0 || rj < 0 || ri >= result.width || rj >= result.height) {
      out[k] = nan;
      continue;
    }
    out[k] = result.at(ri, rj) - truth.z[cells[k]];
  }
}

std::vector<size_t> EvaluatedCells(const Dsm& truth, const std::vector<uint8_t>& mask) {
  std::vector<size_t> cells;
  for (size_t c = 0; c < truth.z.size(); ++c)
    if ((mask.empty() || mask[c]) && std::isfinite(truth.z[c])) cells.push_back(c);
  return cells;
}

std::vector<size_t> Subsample(const std::vector<size_t>& cells, size_t max_count) {
  if (cells.size() <= max_count) return cells;
  std::vector<size_t> sub;
  const double step = double(cells.size()) / double(max_count);
  for (double k = 0; size_t(k) < cells.size(); k += step) sub.push_back(cells[size_t(k)]);
  return sub;
}

struct Candidate {
  int si = 0, sj = 0;
  double score = std::numeric_limits<double>::infinity();  // inf: too little overlap
  double dz = 0;
};

// Per candidate shift: dz = median residual, score = mean(min(|r - dz|, clip)).
void ScoreCandidates(const Dsm& result, const Dsm& truth, const std::vector<size_t>& cells,
                     double clip_m, std::vector<Candidate>& candidates) {
#pragma omp parallel for schedule(dynamic)
  for (long k = 0; k < long(candidates.size()); ++k) {
    Candidate& c = candidates[k];
    std::vector<float> r;
    ShiftedResiduals(result, truth, cells, c.si, c.sj, r);
    std::vector<double> valid;
    valid.reserve(r.size());
    for (float v : r)
      if (std::isfinite(v)) valid.push_back(v);
    // Require a quarter of the cells to overlap so a far shift cannot win on a sliver.
    if (valid.empty() || valid.size() * 4 < cells.size()) continue;
    c.dz = Quantile(valid, 0.5);
    double score = 0;
    for (double v : valid) score += std::min(std::abs(v - c.dz), clip_m);
    c.score = score / valid.size();
  }
}

// Lowest score; ties go to the smaller shift. nullptr if none overlaps enough.
const Candidate* Best(const std::vector<Candidate>& candidates) {
  const Candidate* best = nullptr;
  for (const Candidate& c : candidates) {
    if (!std::isfinite(c.score)) continue;
    const int n = c.si * c.si + c.sj * c.sj;
    if (!best || c.score < best->score - 1e-12 ||
        (c.score <= best->score + 1e-12 && n < best->si * best->si + best->sj * best->sj))
      best = &c;
  }
  return best;
}

}  // namespace

std::string DsmMetricsOptions::Check() const {
  if (!(completeness_threshold_m > 0))
    return "completeness_threshold_m must be > 0, got " + std::to_string(completeness_threshold_m);
  return "";
}

std::string AlignOptions::Check() const {
  if (!(max_shift_m >= 0)) return "max_shift_m must be >= 0, got " + std::to_string(max_shift_m);
  if (max_cells < 100) return "max_cells must be >= 100, got " + std::to_string(max_cells);
  if (!(robust_clip_m > 0)) return "robust_clip_m must be > 0, got " + std::to_string(robust_clip_m);
  return "";
}

std::string DsmEvalOptions::Check() const {
  if (auto m = metrics.Check(); !m.empty()) return "metrics: " + m;
  if (auto m = align.Check(); !m.empty()) return "align: " + m;
  return "";
}

DsmMetrics ComputeDsmMetrics(const std::vector<float>& residuals_m,
                             const DsmMetricsOptions& options) {
  const std::string msg = options.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, "DsmMetricsOptions: " + msg);
  DsmMetrics m;
  m.num_cells = residuals_m.size();
  std::vector<double> r, abs_r;
  r.reserve(residuals_m.size());
  double sum_sq = 0, sum_abs = 0;
  size_t n_c = 0, n_1 = 0, n_05 = 0;
  for (float v : residuals_m) {
    if (!std::isfinite(v)) continue;
    const double a = std::abs(double(v));
    r.push_back(v);
    abs_r.push_back(a);
    sum_abs += a;
    if (a < options.completeness_threshold_m) {
      ++n_c;
      sum_sq += a * a;
    }
    if (a < 1.0) ++n_1;
    if (a < 0.5) ++n_05;
  }
  m.num_valid = r.size();
  if (m.num_cells == 0) return m;
  const double n = double(m.num_cells);
  m.completeness = n_c / n;
  m.completeness_1m = n_1 / n;
  m.completeness_05m = n_05 / n;
  if (r.empty()) return m;
  m.rmse_m = n_c > 0 ? std::sqrt(sum_sq / n_c) : 0.0;
  m.mae_m = sum_abs / r.size();
  m.median_m = Quantile(r, 0.5);
  std::vector<double> dev(r.size());
  for (size_t k = 0; k < r.size(); ++k) dev[k] = std::abs(r[k] - m.median_m);
  m.nmad_m = 1.4826 * Quantile(dev, 0.5);
  m.perc68_m = Quantile(abs_r, 0.68);
  return m;
}

std::vector<float> DsmResiduals(const Dsm& result, const Dsm& truth,
                                const std::vector<uint8_t>& mask, const Alignment& alignment) {
  CheckSameGrid(result, truth, mask);
  std::vector<float> r;
  ShiftedResiduals(result, truth, EvaluatedCells(truth, mask), alignment.shift_i,
                   alignment.shift_j, r);
  for (float& v : r) v += float(alignment.dz_m);
  return r;
}

Alignment AlignDsm(const Dsm& result, const Dsm& truth, const std::vector<uint8_t>& mask,
                   const AlignOptions& options) {
  const std::string msg = options.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, "AlignOptions: " + msg);
  CheckSameGrid(result, truth, mask);
  const std::vector<size_t> all_cells = EvaluatedCells(truth, mask);
  const std::vector<size_t> cells = Subsample(all_cells, options.max_cells);
  const int max_i = int(std::floor(options.max_shift_m / std::abs(truth.geo_transform[1]) + 1e-9));
  const int max_j = int(std::floor(options.max_shift_m / std::abs(truth.geo_transform[5]) + 1e-9));
  // Coarse: every `step`-th shift on a quarter of the cells; fine: +-step around the best.
  const int step = std::max(1, std::max(max_i, max_j) / 4);
  std::vector<Candidate> coarse;
  for (int sj = -(max_j / step) * step; sj <= max_j; sj += step)
    for (int si = -(max_i / step) * step; si <= max_i; si += step) coarse.push_back({si, sj});
  ScoreCandidates(result, truth, Subsample(cells, std::max<size_t>(100, cells.size() / 4)),
                  options.robust_clip_m, coarse);
  const Candidate* best = Best(coarse);
  if (!best) return {};
  std::vector<Candidate> fine;
  for (int sj = best->sj - step; sj <= best->sj + step; ++sj)
    for (int si = best->si - step; si <= best->si + step; ++si)
      if (std::abs(si) <= max_i && std::abs(sj) <= max_j) fine.push_back({si, sj});
  ScoreCandidates(result, truth, cells, options.robust_clip_m, fine);
  best = Best(fine);
  if (!best) return {};
  Alignment a;
  a.shift_i = best->si;
  a.shift_j = best->sj;
  a.dx_m = a.shift_i * truth.geo_transform[1];
  a.dy_m = a.shift_j * truth.geo_transform[5];
  a.dz_m = -best->dz;
  return a;
}

DsmEvaluation EvaluateDsm(const Dsm& result, const Dsm& truth, const std::vector<uint8_t>& mask,
                          const DsmEvalOptions& options) {
  const std::string msg = options.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, "DsmEvalOptions: " + msg);
  CheckSameGrid(result, truth, mask);
  DsmEvaluation e;
  const std::vector<uint8_t> all;  // empty = every cell
  e.alignment = AlignDsm(result, truth, options.align_on_mask ? mask : all, options.align);
  e.mask_raw = ComputeDsmMetrics(DsmResiduals(result, truth, mask), options.metrics);
  e.mask_aligned = ComputeDsmMetrics(DsmResiduals(result, truth, mask, e.alignment), options.metrics);
  e.all_raw = ComputeDsmMetrics(DsmResiduals(result, truth, all), options.metrics);
  e.all_aligned = ComputeDsmMetrics(DsmResiduals(result, truth, all, e.alignment), options.metrics);
  return e;
}

std::vector<uint8_t> MaskFromDsm(const Dsm& mask_grid) {
  std::vector<uint8_t> mask(mask_grid.z.size());
  for (size_t c = 0; c < mask.size(); ++c) mask[c] = mask_grid.z[c] > 0.5f ? 1 : 0;
  return mask;
}

}  // namespace satmesh
