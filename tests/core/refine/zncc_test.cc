#include "core/refine/zncc.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace satmesh {
namespace {

double Energy(const std::vector<float>& a, const std::vector<float>& b,
              const std::vector<uint8_t>& valid, int w, int h, const ZnccOptions& o) {
  return -ComputeZnccField(a, b, valid, w, h, o).sum_zncc;
}

// Direct evaluation of the field in double, window by window (DESIGN.md 3.1).
ZnccField ReferenceField(const std::vector<float>& a, const std::vector<float>& b,
                         const std::vector<uint8_t>& valid, int w, int h, const ZnccOptions& o) {
  const int r = o.window_radius, n_full = (2 * r + 1) * (2 * r + 1);
  ZnccField f;
  f.dM_db.assign(size_t(w) * h, 0.f);
  f.windows.assign(size_t(w) * h, std::nanf(""));
  std::vector<double> dM(size_t(w) * h, 0.0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!valid[y * w + x]) continue;
      double n = 0, sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
      for (int v = std::max(0, y - r); v <= std::min(h - 1, y + r); ++v)
        for (int u = std::max(0, x - r); u <= std::min(w - 1, x + r); ++u) {
          const int q = v * w + u;
          if (!valid[q]) continue;
          n += 1, sa += a[q], sb += b[q], saa += double(a[q]) * a[q];
          sbb += double(b[q]) * b[q], sab += double(a[q]) * b[q];
        }
      if (n < o.min_valid_fraction * n_full) continue;
      const double mu_a = sa / n, mu_b = sb / n;
      const double var_a = std::max(0.0, saa / n - mu_a * mu_a) + o.variance_floor;
      const double var_b = std::max(0.0, sbb / n - mu_b * mu_b) + o.variance_floor;
      const double zncc = (sab / n - mu_a * mu_b) / std::sqrt(var_a * var_b);
      f.sum_zncc += zncc;
      ++f.num_windows;
      f.windows[size_t(y) * w + x] = float(zncc);
      for (int v = std::max(0, y - r); v <= std::min(h - 1, y + r); ++v)
        for (int u = std::max(0, x - r); u <= std::min(w - 1, x + r); ++u) {
          const int q = v * w + u;
          if (!valid[q]) continue;
          dM[q] -= ((a[q] - mu_a) / std::sqrt(var_a * var_b) - zncc * (b[q] - mu_b) / var_b) / n;
        }
    }
  }
  for (size_t q = 0; q < dM.size(); ++q) f.dM_db[q] = float(dM[q]);
  return f;
}

TEST(ComputeZnccField, IdenticalImagesGiveOne) {
  const int w = 20, h = 15;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> a(w * h);
  for (auto& v : a) v = u(rng);
  std::vector<float> b = a;
  for (auto& v : b) v = 3 * v + 1;  // ZNCC is invariant to gain and offset
  const std::vector<uint8_t> valid(w * h, 1);
  ZnccOptions o;
  o.variance_floor = 1e-12;
  const ZnccField f = ComputeZnccField(a, b, valid, w, h, o);
  EXPECT_GT(f.num_windows, 0.9 * w * h);  // corner windows lack valid pixels
  EXPECT_NEAR(f.sum_zncc / f.num_windows, 1.0, 1e-6);
}

TEST(ComputeZnccField, DerivativeMatchesFiniteDifferences) {
  const int w = 17, h = 13;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> a(w * h), b(w * h);
  std::vector<uint8_t> valid(w * h, 1);
  for (int i = 0; i < w * h; ++i) {
    a[i] = u(rng);
    b[i] = 0.6f * a[i] + 0.4f * u(rng);
    if (u(rng) < 0.15f) valid[i] = 0;  // holes: statistics over valid pixels only
  }
  ZnccOptions o;
  o.window_radius = 2;
  o.variance_floor = 1e-3;
  const ZnccField f = ComputeZnccField(a, b, valid, w, h, o);
  int checked = 0;
  for (int p = 0; p < w * h; p += 7) {
    if (!valid[p]) continue;
    const float eps = 1e-2f;
    std::vector<float> bp = b, bm = b;
    bp[p] += eps;
    bm[p] -= eps;
    const double fd = (Energy(a, bp, valid, w, h, o) - Energy(a, bm, valid, w, h, o)) / (2 * eps);
    EXPECT_NEAR(f.dM_db[p], fd, 2e-3 * std::max(1.0, std::abs(fd))) << "pixel " << p;
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

// The field against ReferenceField for window radii 1-3. dirty_workspace: the workspace
// first serves another call (the images swapped), whose rows must not leak into this one.
void ExpectMatchesDirectEvaluation(const std::vector<float>& a, const std::vector<float>& b,
                                   const std::vector<uint8_t>& valid, int w, int h,
                                   bool dirty_workspace) {
  for (int r = 1; r <= 3; ++r) {
    ZnccOptions o;
    o.window_radius = r;
    o.variance_floor = 1e-3;
    o.keep_windows = r != 2;  // the windows kept or not: the same field
    ZnccWorkspace ws;
    if (dirty_workspace) ComputeZnccField(b, a, valid, w, h, o, &ws);
    const ZnccField f = ComputeZnccField(a, b, valid, w, h, o, &ws);
    const ZnccField ref = ReferenceField(a, b, valid, w, h, o);
    if (o.keep_windows) {  // each counted window's ZNCC, NaN exactly where none is counted
      ASSERT_EQ(f.windows.size(), ref.windows.size());
      for (int p = 0; p < w * h; ++p) {
        ASSERT_EQ(std::isnan(f.windows[p]), std::isnan(ref.windows[p]))
            << "radius " << r << " pixel " << p;
        if (!std::isnan(ref.windows[p])) {
          ASSERT_NEAR(f.windows[p], ref.windows[p], 1e-4) << "radius " << r << " pixel " << p;
        }
      }
    } else {
      EXPECT_TRUE(f.windows.empty());
    }
    ASSERT_EQ(f.num_windows, ref.num_windows) << "radius " << r;
    EXPECT_NEAR(f.sum_zncc, ref.sum_zncc, 1e-5 * ref.num_windows) << "radius " << r;
    float max_abs = 0;
    for (float v : ref.dM_db) max_abs = std::max(max_abs, std::abs(v));
    for (int p = 0; p < w * h; ++p)
      ASSERT_NEAR(f.dM_db[p], ref.dM_db[p], 1e-4 * max_abs) << "radius " << r << " pixel " << p;
  }
}

// Tall enough for the streaming sums to run over many rows; offset data and holes.
TEST(ComputeZnccField, MatchesDirectEvaluation) {
  const int w = 53, h = 150;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> a(w * h), b(w * h);
  std::vector<uint8_t> valid(w * h, 1);
  for (int i = 0; i < w * h; ++i) {
    a[i] = 5.f + 0.02f * (i % w) + u(rng);
    b[i] = 0.7f * a[i] + 0.3f * u(rng) - 2.f;
    if (u(rng) < 0.2f || (i / w > 60 && i / w < 70)) valid[i] = 0;
  }
  ExpectMatchesDirectEvaluation(a, b, valid, w, h, /*dirty_workspace=*/false);
}

// Valid pixels on a rotated square inside the image (as a view crop around a rotated
// tile footprint), with holes: the field computes only the valid columns of each band.
TEST(ComputeZnccField, MatchesDirectEvaluationOnARotatedFootprint) {
  const int w = 97, h = 171;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<float> a(w * h), b(w * h);
  std::vector<uint8_t> valid(w * h, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      a[i] = 3.f + 0.03f * x + u(rng);
      b[i] = 0.6f * a[i] + 0.4f * u(rng) + 1.f;
      const float dx = std::abs(x - 0.5f * w), dy = std::abs(y - 0.45f * h);
      valid[i] = dx / (0.45f * w) + dy / (0.4f * h) < 1.f && u(rng) > 0.1f;
    }
  for (int x = 0; x < w; ++x) valid[20 * w + x] = 0;  // an empty row
  ExpectMatchesDirectEvaluation(a, b, valid, w, h, /*dirty_workspace=*/true);
}

}  // namespace
}  // namespace satmesh
