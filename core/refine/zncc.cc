#include "core/refine/zncc.h"

#include <cmath>

namespace satmesh {
namespace {

// Sums of `in` over the (2r+1)² window around each pixel (truncated at the borders), in place.
void BoxSum(std::vector<double>& in_out, int width, int height, int r, std::vector<double>& rows) {
  const std::vector<double>& in = in_out;
  std::vector<double>& out = in_out;
  rows.resize(in.size());
  for (int y = 0; y < height; ++y) {
    const double* src = &in[size_t(y) * width];
    double* dst = &rows[size_t(y) * width];
    double acc = 0;
    for (int x = 0; x <= r && x < width; ++x) acc += src[x];
    for (int x = 0; x < width; ++x) {
      dst[x] = acc;
      if (x + r + 1 < width) acc += src[x + r + 1];
      if (x - r >= 0) acc -= src[x - r];
    }
  }
  std::vector<double> acc(width, 0.0);
  for (int y = 0; y <= r && y < height; ++y)
    for (int x = 0; x < width; ++x) acc[x] += rows[size_t(y) * width + x];
  for (int y = 0; y < height; ++y) {
    double* dst = &out[size_t(y) * width];
    for (int x = 0; x < width; ++x) dst[x] = acc[x];
    if (y + r + 1 < height)
      for (int x = 0; x < width; ++x) acc[x] += rows[size_t(y + r + 1) * width + x];
    if (y - r >= 0)
      for (int x = 0; x < width; ++x) acc[x] -= rows[size_t(y - r) * width + x];
  }
}

}  // namespace

ZnccField ComputeZnccField(const std::vector<float>& a, const std::vector<float>& b,
                           const std::vector<uint8_t>& valid, int width, int height,
                           const ZnccOptions& options, ZnccWorkspace* workspace) {
  ZnccWorkspace local;
  ZnccWorkspace& ws = workspace ? *workspace : local;
  const size_t n = size_t(width) * height;
  const int r = options.window_radius;
  const double min_count = options.min_valid_fraction * (2 * r + 1) * (2 * r + 1);
  const double eps = options.variance_floor;

  for (auto& b : ws.buffers) b.assign(n, 0.0);
  std::vector<double>&v = ws.buffers[0], &va = ws.buffers[1], &vb = ws.buffers[2],
                     &vaa = ws.buffers[3], &vbb = ws.buffers[4], &vab = ws.buffers[5];
  for (size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    v[i] = 1;
    va[i] = a[i];
    vb[i] = b[i];
    vaa[i] = double(a[i]) * a[i];
    vbb[i] = double(b[i]) * b[i];
    vab[i] = double(a[i]) * b[i];
  }
  for (int k = 0; k < 6; ++k) BoxSum(ws.buffers[k], width, height, r, ws.rows);
  const std::vector<double>&s_v = v, &s_a = va, &s_b = vb, &s_aa = vaa, &s_bb = vbb, &s_ab = vab;

  ZnccField field;
  field.zncc.assign(n, 0.f);
  field.dM_db.assign(n, 0.f);
  // Per-window coefficients of the derivative (A..D in DESIGN.md).
  std::vector<double>&A = ws.buffers[6], &B = ws.buffers[7], &C = ws.buffers[8], &D = ws.buffers[9];
  for (size_t i = 0; i < n; ++i) {
    const double count = s_v[i];
    if (!valid[i] || count < min_count) continue;
    const double mu_a = s_a[i] / count, mu_b = s_b[i] / count;
    const double var_a = std::max(0.0, s_aa[i] / count - mu_a * mu_a) + eps;
    const double var_b = std::max(0.0, s_bb[i] / count - mu_b * mu_b) + eps;
    const double cov = s_ab[i] / count - mu_a * mu_b;
    const double sigma_ab = std::sqrt(var_a * var_b);
    const double zncc = cov / sigma_ab;
    field.zncc[i] = float(zncc);
    field.sum_zncc += zncc;
    ++field.num_windows;
    A[i] = 1.0 / (count * sigma_ab);
    B[i] = mu_a * A[i];
    C[i] = zncc / (count * var_b);
    D[i] = mu_b * C[i];
  }
  for (int k = 6; k < 10; ++k) BoxSum(ws.buffers[k], width, height, r, ws.rows);
  const std::vector<double>&sum_A = A, &sum_B = B, &sum_C = C, &sum_D = D;
  for (size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    const double dzncc_db = a[i] * sum_A[i] - sum_B[i] - b[i] * sum_C[i] + sum_D[i];
    field.dM_db[i] = float(-dzncc_db);
  }
  return field;
}

}  // namespace satmesh
