#include "core/refine/zncc.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#if defined(__SSE__)
#include <immintrin.h>
#endif

#include "core/common/simd.h"

namespace satmesh {
namespace {

constexpr int kProducts = 6;      // 1, a, b, a², b², ab
constexpr int kCoefficients = 4;  // A, μ_a·A, C, μ_b·C of the derivative (DESIGN.md)
// Running column sums are re-summed exactly every this many rows, so that float
// rounding cannot drift along the image height.
constexpr int kResumRows = 32;

// Selects without branches: GCC does not if-convert float selects under -frounding-math
// (set for CGAL), so `c ? v : 0.f` and std::max would keep these loops scalar.
inline float Select(bool condition, float v) {
  return std::bit_cast<float>(std::bit_cast<uint32_t>(v) & -uint32_t(condition));
}
inline float ClampNonNegative(float v) { return Select(!(v < 0.f), v); }   // max(0, v)
inline float AtLeastOne(float v) { return v + Select(v < 1.f, 1.f - v); }  // max(1, v)


// Sums of the valid entries of a row of a and b, and their number (float lanes: the
// means only centre the data, any value near them does).
SATMESH_AVX2_CLONE
void MaskedRowSums(const float* __restrict a, const float* __restrict b,
                   const uint8_t* __restrict valid, int n, double* sum_a, double* sum_b,
                   long* count) {
  constexpr int kLanes = 16;
  float lanes_a[kLanes] = {}, lanes_b[kLanes] = {};
  int x = 0;
  for (; x + kLanes <= n; x += kLanes)
    for (int k = 0; k < kLanes; ++k) {
      lanes_a[k] += Select(valid[x + k], a[x + k]);
      lanes_b[k] += Select(valid[x + k], b[x + k]);
    }
  for (; x < n; ++x) {
    lanes_a[0] += Select(valid[x], a[x]);
    lanes_b[0] += Select(valid[x], b[x]);
  }
  for (int k = 0; k < kLanes; ++k) *sum_a += lanes_a[k], *sum_b += lanes_b[k];
  long c = 0;
  for (x = 0; x < n; ++x) c += valid[x] != 0;
  *count += c;
}

// Σ v in double lanes (GCC does not reorder a plain floating-point reduction).
double RowSum(const float* v, int n) {
  double lanes[4] = {};
  int x = 0;
  for (; x + 4 <= n; x += 4)
    for (int k = 0; k < 4; ++k) lanes[k] += v[x + k];
  for (; x < n; ++x) lanes[0] += v[x];
  return (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
}

// v = sqrt(v), SIMD (-frounding-math keeps GCC from vectorising std::sqrt).
void SqrtRow(float* v, int n) {
  int x = 0;
#if defined(__SSE__)
  for (; x + 4 <= n; x += 4) _mm_storeu_ps(v + x, _mm_sqrt_ps(_mm_loadu_ps(v + x)));
#endif
  for (; x < n; ++x) v[x] = std::sqrt(v[x]);
}

// out[c][x] = Σ_{d=-r..r} cols[c][x+d] for `channels` column rows (x = 0 at
// cols + c*stride, with r zeros on both sides). The radius is a template argument for
// the usual windows, so each sum stays in a register.
template <int R>
SATMESH_AVX2_CLONE void BoxSumRowsFixed(const float* cols, int channels, size_t stride, int width,
                                         float* out, size_t out_stride) {
  for (int c = 0; c < channels; ++c) {
    const float* __restrict in = cols + c * stride - R;
    float* __restrict o = out + c * out_stride;
    for (int x = 0; x < width; ++x) {
      float sum = in[x];
      for (int d = 1; d <= 2 * R; ++d) sum += in[x + d];
      o[x] = sum;
    }
  }
}

SATMESH_AVX2_CLONE
void BoxSumRowsAnyRadius(const float* cols, int channels, size_t stride, int width, int r,
                         float* out, size_t out_stride) {
  for (int c = 0; c < channels; ++c) {
    const float* __restrict in = cols + c * stride - r;
    float* __restrict o = out + c * out_stride;
    for (int x = 0; x < width; ++x) o[x] = in[x];
    for (int d = 1; d <= 2 * r; ++d)
      for (int x = 0; x < width; ++x) o[x] += in[x + d];
  }
}

void BoxSumRows(const float* cols, int channels, size_t stride, int width, int r, float* out,
                size_t out_stride) {
  switch (r) {
    case 1:
      return BoxSumRowsFixed<1>(cols, channels, stride, width, out, out_stride);
    case 2:
      return BoxSumRowsFixed<2>(cols, channels, stride, width, out, out_stride);
    case 3:
      return BoxSumRowsFixed<3>(cols, channels, stride, width, out, out_stride);
    case 4:
      return BoxSumRowsFixed<4>(cols, channels, stride, width, out, out_stride);
    default:
      return BoxSumRowsAnyRadius(cols, channels, stride, width, r, out, out_stride);
  }
}

// cols[c] += enter[c] - leave[c] for `channels` rows (row_stride apart in enter and
// leave, stride apart in cols).
SATMESH_AVX2_CLONE
void UpdateColumns(const float* enter, const float* leave, size_t row_stride, int channels,
                   int width, float* cols, size_t stride) {
  for (int c = 0; c < channels; ++c) {
    const float* __restrict in = enter + c * row_stride;
    const float* __restrict out = leave + c * row_stride;
    float* __restrict o = cols + c * stride;
    for (int x = 0; x < width; ++x) o[x] += in[x] - out[x];
  }
}

// Mean of a and b over the valid pixels: both are centred on it before the float box
// sums (ZNCC and its derivative do not change; the sums' rounding shrinks). Any value
// near the mean does, so rows are summed in float lanes, and only every kMeanRowStep-th
// row (all rows of small images).
constexpr int kMeanRowStep = 8;
void ValidMeans(const float* a, const float* b, const uint8_t* valid, int width, int height,
                float* mean_a, float* mean_b) {
  double sa = 0, sb = 0;
  long n = 0;
  const int step = height >= 16 * kMeanRowStep ? kMeanRowStep : 1;
  for (int y = 0; y < height; y += step) {
    const size_t row = size_t(y) * width;
    MaskedRowSums(a + row, b + row, valid + row, width, &sa, &sb, &n);
  }
  *mean_a = n ? float(sa / n) : 0.f;
  *mean_b = n ? float(sb / n) : 0.f;
}

// One image row centred on the means and masked: (valid, a - mean_a, b - mean_b) where
// valid, zeros elsewhere; three rows, row_stride apart, into `out`.
SATMESH_AVX2_CLONE
void CentreRow(const float* __restrict a, const float* __restrict b,
               const uint8_t* __restrict valid, float mean_a, float mean_b, int width,
               float* __restrict out, size_t row_stride) {
  for (int x = 0; x < width; ++x) {
    const bool ok = valid[x];
    out[x] = Select(ok, 1.f);
    out[row_stride + x] = Select(ok, a[x] - mean_a);
    out[2 * row_stride + x] = Select(ok, b[x] - mean_b);
  }
}

// Moves the six product column sums c0..c5 (1, a, b, a², b², ab) down by one row: adds
// the products of the centred row that enters and subtracts those of the one that
// leaves (rows of (m, a, b), row_stride apart). Separate restrict pointers: GCC
// vectorises only then.
SATMESH_AVX2_CLONE
void UpdateProductColumns(const float* __restrict enter, const float* __restrict leave,
                          size_t row_stride, int width, float* __restrict c0, float* __restrict c1,
                          float* __restrict c2, float* __restrict c3, float* __restrict c4,
                          float* __restrict c5) {
  const float *m1 = enter, *a1 = enter + row_stride, *b1 = enter + 2 * row_stride;
  const float *m0 = leave, *a0 = leave + row_stride, *b0 = leave + 2 * row_stride;
  for (int x = 0; x < width; ++x) {
    c0[x] += m1[x] - m0[x];
    c1[x] += a1[x] - a0[x];
    c2[x] += b1[x] - b0[x];
    c3[x] += a1[x] * a1[x] - a0[x] * a0[x];
    c4[x] += b1[x] * b1[x] - b0[x] * b0[x];
    c5[x] += a1[x] * b1[x] - a0[x] * b0[x];
  }
}

// Window statistics of one row from its window sums (kProducts rows, row_stride apart),
// in two passes around a SIMD sqrt. First σ_a² σ_b² (variances floored):
SATMESH_AVX2_CLONE
void VarianceProducts(const float* __restrict sums, size_t row_stride, int width, float eps,
                      float* __restrict out) {
  const float *s0 = sums, *s1 = sums + row_stride, *s2 = sums + 2 * row_stride,
              *s3 = sums + 3 * row_stride, *s4 = sums + 4 * row_stride;
  for (int x = 0; x < width; ++x) {
    const float inv_n = 1.f / AtLeastOne(s0[x]);
    const float mu_a = s1[x] * inv_n, mu_b = s2[x] * inv_n;
    const float var_a = ClampNonNegative(s3[x] * inv_n - mu_a * mu_a) + eps;
    const float var_b = ClampNonNegative(s4[x] * inv_n - mu_b * mu_b) + eps;
    out[x] = var_a * var_b;
  }
}

// Then, with sigma_ab = σ_a σ_b: the derivative coefficients (kCoefficients rows of the
// given stride, zero where the window is not counted), ZNCC per counted window (0
// elsewhere); returns the number of counted windows.
SATMESH_AVX2_CLONE
long Coefficients(const float* __restrict sums, size_t row_stride, const float* __restrict sigma_ab,
                  const float* __restrict valid, int width, float eps, float min_count,
                  float* __restrict zncc_out, float* __restrict coefficients, size_t stride) {
  const float *s0 = sums, *s1 = sums + row_stride, *s2 = sums + 2 * row_stride,
              *s4 = sums + 4 * row_stride, *s5 = sums + 5 * row_stride;
  float* __restrict k0 = coefficients;
  float* __restrict k1 = coefficients + stride;
  float* __restrict k2 = coefficients + 2 * stride;
  float* __restrict k3 = coefficients + 3 * stride;
  long count = 0;
  for (int x = 0; x < width; ++x) {
    const bool ok = (valid[x] != 0.f) & (s0[x] >= min_count);
    const float inv_n = 1.f / AtLeastOne(s0[x]);
    const float mu_a = s1[x] * inv_n, mu_b = s2[x] * inv_n;
    const float var_b = ClampNonNegative(s4[x] * inv_n - mu_b * mu_b) + eps;
    const float cov = s5[x] * inv_n - mu_a * mu_b;
    const float zncc = cov / sigma_ab[x];
    const float A = Select(ok, inv_n / sigma_ab[x]);
    const float C = Select(ok, zncc * inv_n / var_b);
    zncc_out[x] = Select(ok, zncc);
    count += ok;
    k0[x] = A;
    k1[x] = mu_a * A;
    k2[x] = C;
    k3[x] = mu_b * C;
  }
  return count;
}

// ∂M/∂b of one centred row from its box-summed coefficients (all rows row_stride apart).
SATMESH_AVX2_CLONE
void DerivativeRow(const float* __restrict centred, const float* __restrict sums, size_t row_stride,
                   int width, float* __restrict dM_db) {
  const float *m = centred, *a = centred + row_stride, *b = centred + 2 * row_stride;
  const float *s0 = sums, *s1 = sums + row_stride, *s2 = sums + 2 * row_stride,
              *s3 = sums + 3 * row_stride;
  for (int x = 0; x < width; ++x) {
    const float d = -(a[x] * s0[x] - s1[x] - b[x] * s2[x] + s3[x]);
    dM_db[x] = Select(m[x] != 0.f, d);
  }
}

// Per band of kResumRows rows: the columns [first, second) of its valid pixels,
// widened by r and clipped to the image ({0, 0} when the band has none).
void BandSpans(const uint8_t* valid, int width, int height, int r,
               std::vector<std::pair<int, int>>* spans) {
  spans->assign((height + kResumRows - 1) / kResumRows, {0, 0});
  for (size_t band = 0; band < spans->size(); ++band) {
    int lo = width, hi = 0;
    for (int y = int(band) * kResumRows; y < std::min(height, int(band + 1) * kResumRows); ++y) {
      const uint8_t* row = valid + size_t(y) * width;
      int first = 0, last = width;  // the row's valid pixels lie in [first, last)
      while (first < width && !row[first]) ++first;
      if (first == width) continue;
      while (!row[last - 1]) --last;
      lo = std::min(lo, first), hi = std::max(hi, last);
    }
    if (lo < hi) (*spans)[band] = {std::max(0, lo - r), std::min(width, hi + r)};
  }
}

}  // namespace

// Streams over rows. Products: running column sums over rows y-r..y+r (add the row that
// enters, subtract the one that leaves), then horizontal box sums give the window sums
// of row y and its statistics, whose derivative coefficients go into a ring of 2r+2
// rows. Coefficients: the same running column sums over that ring give ∂M/∂b of row
// y-r. Rows outside the image are zero. Sums and statistics are float (SIMD width)
// over centred values; column sums are re-summed exactly every kResumRows rows.
// Only the columns that matter are computed: in each band of kResumRows rows (both
// passes restart their column sums there), the valid pixels' columns widened by r.
// Outside it nothing is read (window statistics and ∂M/∂b are needed at valid pixels
// only, and reach r columns out); coefficient rows are zero there. A view's pixels
// that see no surface (a crop is the box of a rotated footprint) cost nothing.
void ComputeZnccFieldInto(const std::vector<float>& a_image, const std::vector<float>& b_image,
                          const std::vector<uint8_t>& valid_image, int width, int height,
                          const ZnccOptions& options, ZnccField* field_out,
                          ZnccWorkspace* workspace) {
  ZnccWorkspace local;
  ZnccWorkspace& ws = workspace ? *workspace : local;
  const int w = width, h = height, r = options.window_radius, slots = 2 * r + 2;
  const float min_count = float(std::ceil(options.min_valid_fraction * (2 * r + 1) * (2 * r + 1)));
  const float eps = float(options.variance_floor);
  const size_t stride = size_t(w) + 2 * r;  // column sum rows, r zeros on both sides
  const float *a = a_image.data(), *b = b_image.data();
  const uint8_t* valid = valid_image.data();

  float mean_a, mean_b;
  ValidMeans(a, b, valid, w, h, &mean_a, &mean_b);
  // Columns [first, second) computed in each band of kResumRows rows.
  BandSpans(valid, w, h, r, &ws.band_spans);
  const auto span = [&](int y) { return ws.band_spans[y / kResumRows]; };

  ZnccField& field = *field_out;
  field.dM_db.resize(size_t(w) * h);
  // Work rows a little more than w apart (rows 4 KiB apart slow the loads that follow
  // stores to another row).
  const size_t row_stride = (size_t(w) + 15) / 16 * 16 + 16;
  ws.centred_ring.resize(slots * 3 * row_stride);
  ws.coefficient_ring.resize(slots * kCoefficients * row_stride);
  ws.columns.assign((kProducts + kCoefficients) * stride, 0.f);
  ws.rows.resize((kProducts + 2) * row_stride);
  ws.zeros.assign(std::max(3, kCoefficients) * row_stride, 0.f);
  // Columns each coefficient ring slot may hold non-zeros in (unknown on entry).
  ws.slot_written.assign(slots, {0, w});
  float* product_cols = ws.columns.data() + r;  // kProducts rows, x = 0 at offset r
  float* coefficient_cols = product_cols + kProducts * stride;
  float* sums = ws.rows.data();  // kProducts rows of window sums
  float* sigma_ab = sums + kProducts * row_stride;
  float* zncc = sigma_ab + row_stride;
  // Rows k of the rings: centred (m, a, b) and derivative coefficients.
  const auto centred = [&](int k) { return &ws.centred_ring[(k % slots) * 3 * row_stride]; };
  const auto coefficients = [&](int k) {
    return &ws.coefficient_ring[(k % slots) * kCoefficients * row_stride];
  };
  const auto centre = [&](int k) {
    const size_t row = size_t(k) * w;
    CentreRow(a + row, b + row, valid + row, mean_a, mean_b, w, centred(k), row_stride);
  };
  // Running column sums of `channels` rows over the ring rows y-r..y+r; rows outside
  // the image are the zero row.
  const float* zeros = ws.zeros.data();
  // Columns outside the band's span stay zero from the band's first row.
  const auto update_columns = [&](int y, const auto& update, int channels, float* cols) {
    const auto [x0, x1] = span(y);
    if (y % kResumRows == 0) {
      for (int c = 0; c < channels; ++c) std::fill_n(cols + c * stride, w, 0.f);
      for (int k = std::max(0, y - r); k <= std::min(h - 1, y + r); ++k) update(k, -1, x0, x1);
    } else {
      update(y + r, y - r - 1, x0, x1);
    }
  };
  const auto update_products = [&](int enter, int leave, int x0, int x1) {
    float* c = product_cols + x0;
    UpdateProductColumns((enter < h ? centred(enter) : zeros) + x0,
                         (leave >= 0 ? centred(leave) : zeros) + x0, row_stride, x1 - x0, c,
                         c + stride, c + 2 * stride, c + 3 * stride, c + 4 * stride,
                         c + 5 * stride);
  };
  const auto update_coefficients = [&](int enter, int leave, int x0, int x1) {
    UpdateColumns((enter < h ? coefficients(enter) : zeros) + x0,
                  (leave >= 0 ? coefficients(leave) : zeros) + x0, row_stride, kCoefficients,
                  x1 - x0, coefficient_cols + x0, stride);
  };
  // Before coefficient row t is written on [x0, x1): zeros where its slot held an older
  // row outside that range.
  const auto clear_slot = [&](int t, int x0, int x1) {
    auto& [old0, old1] = ws.slot_written[t % slots];
    float* k = coefficients(t);
    for (int c = 0; c < kCoefficients; ++c) {
      float* row = k + c * row_stride;
      if (old0 < std::min(old1, x0)) std::fill(row + old0, row + std::min(old1, x0), 0.f);
      if (std::max(old0, x1) < old1) std::fill(row + std::max(old0, x1), row + old1, 0.f);
    }
    old0 = x0, old1 = x1;
  };

  double sum_zncc = 0;
  long num_windows = 0;
  if (options.keep_windows) field.windows.assign(size_t(w) * h, std::nanf(""));
  else field.windows.clear();
  for (int k = 0; k < std::min(r, h); ++k) centre(k);
  for (int t = 0; t < h + r; ++t) {
    // Window statistics of row t: derivative coefficients into the ring.
    if (t < h) {
      if (t + r < h) centre(t + r);
      const auto [x0, x1] = span(t);
      const int n = x1 - x0;
      clear_slot(t, x0, x1);
      if (n > 0) {
        update_columns(t, update_products, kProducts, product_cols);
        BoxSumRows(product_cols + x0, kProducts, stride, n, r, sums + x0, row_stride);
        VarianceProducts(sums + x0, row_stride, n, eps, sigma_ab + x0);
        SqrtRow(sigma_ab + x0, n);
        num_windows += Coefficients(sums + x0, row_stride, sigma_ab + x0, centred(t) + x0, n, eps,
                                    min_count, zncc + x0, coefficients(t) + x0, row_stride);
        sum_zncc += RowSum(zncc + x0, n);
        if (options.keep_windows) {  // the windows Coefficients counted
          const float* m = centred(t);
          float* out = &field.windows[size_t(t) * w];
          for (int x = x0; x < x1; ++x)
            if (m[x] != 0.f && sums[x] >= min_count) out[x] = zncc[x];
        }
      }
    }
    // ∂M/∂b of row y = t - r from the coefficients of rows y-r..y+r.
    const int y = t - r;
    if (y < 0) continue;
    const auto [x0, x1] = span(y);
    float* dM_db = &field.dM_db[size_t(y) * w];
    std::fill(dM_db, dM_db + x0, 0.f);
    std::fill(dM_db + std::max(x0, x1), dM_db + w, 0.f);
    if (x1 <= x0) continue;
    update_columns(y, update_coefficients, kCoefficients, coefficient_cols);
    BoxSumRows(coefficient_cols + x0, kCoefficients, stride, x1 - x0, r, sums + x0, row_stride);
    DerivativeRow(centred(y) + x0, sums + x0, row_stride, x1 - x0, dM_db + x0);
  }
  field.sum_zncc = sum_zncc;
  field.num_windows = num_windows;
}

ZnccField ComputeZnccField(const std::vector<float>& a, const std::vector<float>& b,
                           const std::vector<uint8_t>& valid, int width, int height,
                           const ZnccOptions& options, ZnccWorkspace* workspace) {
  ZnccField field;
  ComputeZnccFieldInto(a, b, valid, width, height, options, &field, workspace);
  return field;
}

}  // namespace satmesh
