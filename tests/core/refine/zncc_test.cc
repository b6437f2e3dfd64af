#include "core/refine/zncc.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace satmesh {
namespace {

double Energy(const std::vector<float>& a, const std::vector<float>& b,
              const std::vector<uint8_t>& valid, int w, int h, const ZnccOptions& o) {
  return -ComputeZnccField(a, b, valid, w, h, o).sum_zncc;
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

}  // namespace
}  // namespace satmesh
