#include "core/refine/zncc.h"

#include <algorithm>
#include <cmath>

namespace satmesh {
namespace {

// In-place box sums of K interleaved channels (data[pixel * K + k]) over the (2r+1)²
// window around each pixel, truncated at the borders. One pass per direction for all
// channels keeps the memory traffic down (this is the ZNCC's hot loop).
template <int K>
void BoxSumInterleaved(std::vector<double>& data, int width, int height, int r,
                       std::vector<double>& rows) {
  rows.resize(data.size());
  for (int y = 0; y < height; ++y) {
    const double* src = &data[size_t(y) * width * K];
    double* dst = &rows[size_t(y) * width * K];
    double acc[K] = {};
    for (int x = 0; x <= r && x < width; ++x)
      for (int k = 0; k < K; ++k) acc[k] += src[x * K + k];
    for (int x = 0; x < width; ++x) {
      for (int k = 0; k < K; ++k) dst[x * K + k] = acc[k];
      if (x + r + 1 < width)
        for (int k = 0; k < K; ++k) acc[k] += src[(x + r + 1) * K + k];
      if (x - r >= 0)
        for (int k = 0; k < K; ++k) acc[k] -= src[(x - r) * K + k];
    }
  }
  const size_t row_len = size_t(width) * K;
  std::vector<double> acc(row_len, 0.0);
  for (int y = 0; y <= r && y < height; ++y) {
    const double* src = &rows[y * row_len];
    for (size_t i = 0; i < row_len; ++i) acc[i] += src[i];
  }
  for (int y = 0; y < height; ++y) {
    std::copy(acc.begin(), acc.end(), data.begin() + y * row_len);
    if (y + r + 1 < height) {
      const double* add = &rows[(y + r + 1) * row_len];
      for (size_t i = 0; i < row_len; ++i) acc[i] += add[i];
    }
    if (y - r >= 0) {
      const double* sub = &rows[(y - r) * row_len];
      for (size_t i = 0; i < row_len; ++i) acc[i] -= sub[i];
    }
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

  // Window sums of 1, a, b, a², b², ab over valid pixels.
  std::vector<double>& sums = ws.buffers[0];
  sums.resize(6 * n);
  for (size_t i = 0; i < n; ++i) {
    double* s = &sums[6 * i];
    if (!valid[i]) {
      std::fill(s, s + 6, 0.0);
      continue;
    }
    const double ai = a[i], bi = b[i];
    s[0] = 1, s[1] = ai, s[2] = bi, s[3] = ai * ai, s[4] = bi * bi, s[5] = ai * bi;
  }
  BoxSumInterleaved<6>(sums, width, height, r, ws.rows);

  ZnccField field;
  field.zncc.assign(n, 0.f);
  field.dM_db.assign(n, 0.f);
  // Per-window coefficients of the derivative (A..D in DESIGN.md), summed over windows.
  std::vector<double>& coeffs = ws.buffers[1];
  coeffs.resize(4 * n);
  for (size_t i = 0; i < n; ++i) {
    double* c = &coeffs[4 * i];
    const double* s = &sums[6 * i];
    const double count = s[0];
    if (!valid[i] || count < min_count) {
      std::fill(c, c + 4, 0.0);
      continue;
    }
    const double mu_a = s[1] / count, mu_b = s[2] / count;
    const double var_a = std::max(0.0, s[3] / count - mu_a * mu_a) + eps;
    const double var_b = std::max(0.0, s[4] / count - mu_b * mu_b) + eps;
    const double cov = s[5] / count - mu_a * mu_b;
    const double sigma_ab = std::sqrt(var_a * var_b);
    const double zncc = cov / sigma_ab;
    field.zncc[i] = float(zncc);
    field.sum_zncc += zncc;
    ++field.num_windows;
    c[0] = 1.0 / (count * sigma_ab);  // A
    c[1] = mu_a * c[0];               // B
    c[2] = zncc / (count * var_b);    // C
    c[3] = mu_b * c[2];               // D
  }
  BoxSumInterleaved<4>(coeffs, width, height, r, ws.rows);
  for (size_t i = 0; i < n; ++i) {
    if (!valid[i]) continue;
    const double* c = &coeffs[4 * i];
    const double dzncc_db = a[i] * c[0] - c[1] - b[i] * c[2] + c[3];
    field.dM_db[i] = float(-dzncc_db);
  }
  return field;
}

}  // namespace satmesh
