#include "core/refine/zncc.h"

#include <algorithm>
#include <cmath>

namespace satmesh {
namespace {

constexpr int kProducts = 6;      // 1, a, b, a², b², ab
constexpr int kCoefficients = 4;  // A, B, C, D of the derivative (DESIGN.md)

// Horizontal (2r+1)-box sums of `channels` padded rows (stride width+2r, zeros in the
// pads, so truncation at the borders is implicit) into `out` (stride width).
void BoxSumRows(const float* padded, int channels, int width, int r, float* out) {
  const size_t stride = size_t(width) + 2 * r;
  for (int c = 0; c < channels; ++c) {
    const float* in = padded + c * stride;
    float* o = out + size_t(c) * width;
    for (int x = 0; x < width; ++x) o[x] = in[x];
    for (int d = 1; d <= 2 * r; ++d)
      for (int x = 0; x < width; ++x) o[x] += in[x + d];
  }
}

// Vertical sum of the ring's 2r+1 rows (each `channels` x width) into `out`.
void SumRing(const float* ring, int slots, int channels, int width, float* out) {
  const size_t row = size_t(channels) * width;
  std::copy(ring, ring + row, out);
  for (int k = 1; k < slots; ++k) {
    const float* in = ring + k * row;
    for (size_t i = 0; i < row; ++i) out[i] += in[i];
  }
}

// Mean of a and b over the valid pixels: both are centred on it before the float box
// sums (ZNCC and its derivative do not change; the sums' rounding shrinks).
void ValidMeans(const std::vector<float>& a, const std::vector<float>& b,
                const std::vector<uint8_t>& valid, float* mean_a, float* mean_b) {
  double sa = 0, sb = 0;
  long n = 0;
  for (size_t i = 0; i < valid.size(); ++i)
    if (valid[i]) sa += a[i], sb += b[i], ++n;
  *mean_a = n ? float(sa / n) : 0.f;
  *mean_b = n ? float(sb / n) : 0.f;
}

}  // namespace

// Streams over rows with two rings of 2r+1 horizontally box-summed rows: products
// (window statistics of row y need rows y-r..y+r) and derivative coefficients (∂M/∂b of
// row y needs the coefficients of rows y-r..y+r). Rows outside the image are zero. Sums
// are float (SIMD width) over centred values; each window's statistics are double.
ZnccField ComputeZnccField(const std::vector<float>& a, const std::vector<float>& b,
                           const std::vector<uint8_t>& valid, int width, int height,
                           const ZnccOptions& options, ZnccWorkspace* workspace) {
  ZnccWorkspace local;
  ZnccWorkspace& ws = workspace ? *workspace : local;
  const int w = width, h = height, r = options.window_radius, slots = 2 * r + 1;
  const double min_count = options.min_valid_fraction * slots * slots;
  const double eps = options.variance_floor;
  const size_t stride = size_t(w) + 2 * r;

  float mean_a, mean_b;
  ValidMeans(a, b, valid, &mean_a, &mean_b);

  ZnccField field;
  field.dM_db.assign(size_t(w) * h, 0.f);
  ws.product_rows.assign(size_t(slots) * kProducts * w, 0.f);
  ws.coefficient_rows.assign(size_t(slots) * kCoefficients * w, 0.f);
  ws.scratch.assign(kProducts * stride + kProducts * size_t(w), 0.f);
  float* padded = ws.scratch.data();                 // kProducts padded rows
  float* sums = padded + kProducts * stride;         // kProducts rows of window sums
  double sum_zncc = 0;
  long num_windows = 0;

  for (int t = 0; t < h + 2 * r; ++t) {
    // Stage 1: products of row t, box-summed horizontally, into the product ring.
    if (t < h) {
      const size_t row = size_t(t) * w;
      for (int x = 0; x < w; ++x) {
        const bool ok = valid[row + x];
        const float ai = ok ? a[row + x] - mean_a : 0.f, bi = ok ? b[row + x] - mean_b : 0.f;
        float* p = padded + r + x;
        p[0] = ok ? 1.f : 0.f;
        p[stride] = ai;
        p[2 * stride] = bi;
        p[3 * stride] = ai * ai;
        p[4 * stride] = bi * bi;
        p[5 * stride] = ai * bi;
      }
      BoxSumRows(padded, kProducts, w, r, &ws.product_rows[size_t(t % slots) * kProducts * w]);
    } else {
      std::fill_n(&ws.product_rows[size_t(t % slots) * kProducts * w], kProducts * w, 0.f);
    }
    // Stage 2: window statistics of row y = t - r, coefficients into the coefficient ring.
    const int y = t - r;
    float* coeff_slot = nullptr;
    if (y >= 0) coeff_slot = &ws.coefficient_rows[size_t(y % slots) * kCoefficients * w];
    if (y >= 0 && y < h) {
      SumRing(ws.product_rows.data(), slots, kProducts, w, sums);
      const size_t row = size_t(y) * w;
      float* c = padded;  // reuse: kCoefficients padded rows
      for (int x = 0; x < w; ++x) {
        const double count = sums[x];
        const bool ok = valid[row + x] && count >= min_count;
        const double n = std::max(count, 1.0);
        const double mu_a = sums[w + x] / n, mu_b = sums[2 * w + x] / n;
        const double var_a = std::max(0.0, sums[3 * w + x] / n - mu_a * mu_a) + eps;
        const double var_b = std::max(0.0, sums[4 * w + x] / n - mu_b * mu_b) + eps;
        const double cov = sums[5 * w + x] / n - mu_a * mu_b;
        const double sigma_ab = std::sqrt(var_a * var_b);
        const double zncc = cov / sigma_ab;
        sum_zncc += ok ? zncc : 0.0;
        num_windows += ok;
        const double A = ok ? 1.0 / (n * sigma_ab) : 0.0;
        const double C = ok ? zncc / (n * var_b) : 0.0;
        c[r + x] = float(A);
        c[stride + r + x] = float(mu_a * A);
        c[2 * stride + r + x] = float(C);
        c[3 * stride + r + x] = float(mu_b * C);
      }
      BoxSumRows(padded, kCoefficients, w, r, coeff_slot);
    } else if (y >= h) {
      std::fill_n(coeff_slot, kCoefficients * w, 0.f);
    }
    // Stage 3: ∂M/∂b of row y2 = t - 2r.
    const int y2 = t - 2 * r;
    if (y2 >= 0) {
      SumRing(ws.coefficient_rows.data(), slots, kCoefficients, w, sums);
      const size_t row = size_t(y2) * w;
      for (int x = 0; x < w; ++x) {
        if (!valid[row + x]) continue;
        const float ai = a[row + x] - mean_a, bi = b[row + x] - mean_b;
        field.dM_db[row + x] = -(ai * sums[x] - sums[w + x] - bi * sums[2 * w + x] + sums[3 * w + x]);
      }
    }
  }
  field.sum_zncc = sum_zncc;
  field.num_windows = num_windows;
  return field;
}

}  // namespace satmesh
