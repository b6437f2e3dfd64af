#include "core/image/image.h"

#include <gtest/gtest.h>

#include <random>

#include <cmath>

#include "core/common/error.h"

namespace satmesh {
namespace {

// f(col, row) = a + b*x + c*y evaluated at the pixel centre (x, y) = (col+0.5, row+0.5).
ImageF LinearRamp(int w, int h, double a, double b, double c) {
  ImageF image(w, h);
  for (int r = 0; r < h; ++r)
    for (int col = 0; col < w; ++col) image.at(col, r) = float(a + b * (col + 0.5) + c * (r + 0.5));
  return image;
}

TEST(SampleBilinear, PixelCentreGivesPixelValue) {
  ImageF image(3, 2);
  for (int i = 0; i < 6; ++i) image.pixels[i] = float(i * i);
  float v = -1;
  ASSERT_TRUE(SampleBilinear(image, 1.5, 1.5, &v));
  EXPECT_FLOAT_EQ(v, image.at(1, 1));
  ASSERT_TRUE(SampleBilinear(image, 2.5, 1.5, &v));  // last centre is inside
  EXPECT_FLOAT_EQ(v, image.at(2, 1));
}

TEST(SampleBilinear, ReproducesLinearFunctionExactly) {
  const ImageF image = LinearRamp(8, 6, 3.0, 2.0, -0.5);
  for (double x : {0.5, 1.25, 3.7, 7.5})
    for (double y : {0.5, 2.1, 5.5}) {
      float v = 0;
      ASSERT_TRUE(SampleBilinear(image, x, y, &v)) << x << "," << y;
      EXPECT_NEAR(v, 3.0 + 2.0 * x - 0.5 * y, 1e-5);
    }
}

TEST(SampleBilinear, OutsideCentresReturnsFalseAndKeepsOutput) {
  const ImageF image = LinearRamp(4, 4, 0, 1, 1);
  float v = 42.f;
  EXPECT_FALSE(SampleBilinear(image, 0.49, 2.0, &v));
  EXPECT_FALSE(SampleBilinear(image, 2.0, 3.51, &v));
  EXPECT_FALSE(SampleBilinear(image, std::nan(""), 2.0, &v));
  EXPECT_EQ(v, 42.f);
}

TEST(SampleBilinearWithGradient, MatchesFiniteDifferences) {
  ImageF image(5, 5);
  for (int i = 0; i < 25; ++i) image.pixels[i] = float(std::sin(0.7 * i) * 10);
  const double x = 2.3, y = 1.8, h = 1e-3;
  float v, gx, gy, vxp, vxm, vyp, vym;
  ASSERT_TRUE(SampleBilinearWithGradient(image, x, y, &v, &gx, &gy));
  ASSERT_TRUE(SampleBilinear(image, x + h, y, &vxp) && SampleBilinear(image, x - h, y, &vxm));
  ASSERT_TRUE(SampleBilinear(image, x, y + h, &vyp) && SampleBilinear(image, x, y - h, &vym));
  EXPECT_NEAR(gx, (vxp - vxm) / (2 * h), 2e-2);
  EXPECT_NEAR(gy, (vyp - vym) / (2 * h), 2e-2);
  float v2;
  ASSERT_TRUE(SampleBilinear(image, x, y, &v2));
  EXPECT_FLOAT_EQ(v, v2);
}

TEST(ComputeGradients, LinearRampHasConstantGradient) {
  const ImageF image = LinearRamp(7, 5, 1.0, 0.25, -2.0);
  ImageF gx, gy;
  ComputeGradients(image, &gx, &gy);
  ASSERT_EQ(gx.width, 7);
  ASSERT_EQ(gy.height, 5);
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 7; ++c) {
      EXPECT_NEAR(gx.at(c, r), 0.25, 1e-5) << c << "," << r;  // borders included
      EXPECT_NEAR(gy.at(c, r), -2.0, 1e-5) << c << "," << r;
    }
}

TEST(GaussianPyramid, SizesAreCeilOfHalves) {
  const auto pyramid = GaussianPyramid(ImageF(13, 8, 1.f), 4);
  ASSERT_EQ(pyramid.size(), 4u);
  const int widths[] = {13, 7, 4, 2}, heights[] = {8, 4, 2, 1};
  for (int l = 0; l < 4; ++l) {
    EXPECT_EQ(pyramid[l].width, widths[l]);
    EXPECT_EQ(pyramid[l].height, heights[l]);
  }
  EXPECT_NEAR(pyramid[3].at(1, 0), 1.f, 1e-6);  // constants stay constant
}

TEST(GaussianPyramid, LinearRampAgreesAcrossLevelsInCornerOriginGrid) {
  // A level-0 point (x, y) is (x, y) / 2^l at level l. On a linear ramp, smoothing does
  // not change values away from the borders, so the samples must agree.
  const double a = 5.0, b = 0.75, c = -0.3;
  const auto pyramid = GaussianPyramid(LinearRamp(192, 192, a, b, c), 4);
  for (double x : {70.0, 85.3, 99.5}) {
    for (double y : {72.0, 88.7, 110.1}) {
      for (int l = 0; l < 4; ++l) {
        const double s = std::ldexp(1.0, -l);
        float v = 0;
        ASSERT_TRUE(SampleBilinear(pyramid[l], x * s, y * s, &v));
        EXPECT_NEAR(v, a + b * x + c * y, 2e-3) << "level " << l << " at " << x << "," << y;
      }
    }
  }
}

TEST(GaussianPyramid, RejectsZeroLevels) {
  EXPECT_THROW(GaussianPyramid(ImageF(4, 4), 0), Error);
}

TEST(NormalizeRadiometry, PercentilesMapToZeroAndOne) {
  ImageF image(101, 1);
  for (int i = 0; i <= 100; ++i) image.pixels[i] = float(1000 + 10 * i);  // 11-bit-ish
  RadiometryOptions options;
  options.low_percentile = 10;
  options.high_percentile = 90;
  const ImageF out = NormalizeRadiometry(image, options);
  EXPECT_NEAR(out.pixels[10], 0.0, 1e-6);
  EXPECT_NEAR(out.pixels[90], 1.0, 1e-6);
  EXPECT_NEAR(out.pixels[50], 0.5, 1e-6);
  EXPECT_NEAR(out.pixels[0], -0.125, 1e-6);  // not clipped
  EXPECT_NEAR(out.pixels[100], 1.125, 1e-6);
}

TEST(NormalizeRadiometry, ConstantImageIsShiftedOnly) {
  const ImageF out = NormalizeRadiometry(ImageF(4, 4, 7.f));
  for (float v : out.pixels) EXPECT_EQ(v, 0.f);
}

TEST(RadiometryOptions, DefaultsAreValid) { EXPECT_EQ(RadiometryOptions{}.Check(), ""); }

TEST(RadiometryOptions, InvalidPercentilesRejected) {
  RadiometryOptions options;
  options.high_percentile = 40;
  EXPECT_NE(options.Check().find("high_percentile"), std::string::npos);
  EXPECT_THROW(NormalizeRadiometry(ImageF(2, 2), options), Error);
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

TEST(NoiseSigma, RecoversTheNoiseOfASmoothImage) {
  // A smooth ramp plus Gaussian noise of known sigma: the Laplacian-difference mask
  // cancels the ramp, so the estimate is the noise.
  std::mt19937 gen(7);
  for (const double sigma : {0.005, 0.02}) {
    std::normal_distribution<float> noise(0.f, float(sigma));
    ImageF image(300, 200);
    for (int r = 0; r < 200; ++r)
      for (int c = 0; c < 300; ++c) image.at(c, r) = 0.3f + 0.001f * c + 0.0005f * r + noise(gen);
    EXPECT_NEAR(NoiseSigma(image), sigma, 0.05 * sigma);
  }
  EXPECT_EQ(NoiseSigma(ImageF(2, 2, 1.f)), 0.0);
  EXPECT_NEAR(NoiseSigma(ImageF(50, 50, 0.7f)), 0.0, 1e-9);
}

}  // namespace
}  // namespace satmesh
