#include "core/synth/initial_dsm.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/common/error.h"

namespace satmesh::synth {
namespace {

// Smooth Gaussian random field with unit standard deviation.
cv::Mat SmoothNoise(int w, int h, double sigma_px, std::mt19937_64& gen) {
  cv::Mat m(h, w, CV_32F);
  std::normal_distribution<float> n(0.f, 1.f);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) m.at<float>(j, i) = n(gen);
  if (sigma_px > 0.3) cv::GaussianBlur(m, m, cv::Size(0, 0), sigma_px, sigma_px, cv::BORDER_REFLECT);
  cv::Scalar mean, stddev;
  cv::meanStdDev(m, mean, stddev);
  if (stddev[0] > 0) m = (m - mean[0]) / stddev[0];
  return m;
}

}  // namespace

std::string DegradeOptions::Check() const {
  for (double v : {fattening_m, blur_sigma_m, noise_sigma_m, white_noise_m, blobs_per_hectare,
                   blob_height_m, holes_per_hectare})
    if (!(v >= 0)) return "amounts, sizes and densities must be >= 0";
  if (!(noise_correlation_m > 0) || !(hole_radius_m > 0)) return "lengths must be > 0";
  return "";
}

Dsm DegradeDsm(const Dsm& truth, const DegradeOptions& o, uint64_t seed) {
  const std::string why = o.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "DegradeOptions: " + why);
  SATMESH_CHECK(truth.width > 0 && truth.height > 0, ErrorCode::kInvalidArgument,
                "DegradeDsm: empty grid");
  const int w = truth.width, h = truth.height;
  const double gsd = std::abs(truth.geo_transform[1]);
  std::mt19937_64 gen(seed * 0x2545F4914F6CDD1Dull + 3);
  cv::Mat z(h, w, CV_32F, const_cast<float*>(truth.z.data()));
  z = z.clone();
  // Fill NaN cells from below (lowest valid value) so filters stay defined.
  float lowest = 1e30f;
  for (float v : truth.z)
    if (std::isfinite(v)) lowest = std::min(lowest, v);
  cv::patchNaNs(z, lowest < 1e30f ? lowest : 0.f);
  // Edge fattening: the higher side spreads over the lower one.
  const int r = int(std::round(o.fattening_m / gsd));
  if (r > 0) {
    cv::Mat kernel = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
    cv::dilate(z, z, kernel, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  }
  if (o.blur_sigma_m > 0)
    cv::GaussianBlur(z, z, cv::Size(0, 0), o.blur_sigma_m / gsd, o.blur_sigma_m / gsd, cv::BORDER_REPLICATE);
  if (o.noise_sigma_m > 0) z += o.noise_sigma_m * SmoothNoise(w, h, o.noise_correlation_m / gsd, gen);
  if (o.white_noise_m > 0) z += o.white_noise_m * SmoothNoise(w, h, 0, gen);
  const double hectares = w * h * gsd * gsd / 1e4;
  std::uniform_real_distribution<double> u(0, 1);
  const int blobs = int(std::round(o.blobs_per_hectare * hectares * (0.5 + u(gen))));
  for (int b = 0; b < blobs; ++b) {
    const double cx = u(gen) * w, cy = u(gen) * h, rad = (2 + 4 * u(gen)) / gsd;
    const double amp = o.blob_height_m * (2 * u(gen) - 1);
    const int r0 = int(3 * rad);
    for (int j = std::max(0, int(cy) - r0); j < std::min(h, int(cy) + r0); ++j)
      for (int i = std::max(0, int(cx) - r0); i < std::min(w, int(cx) + r0); ++i) {
        const double d2 = ((i - cx) * (i - cx) + (j - cy) * (j - cy)) / (rad * rad);
        z.at<float>(j, i) += float(amp * std::exp(-0.5 * d2));
      }
  }
  // Holes: irregular blobs from a thresholded smooth field inside random disks.
  const cv::Mat shape = SmoothNoise(w, h, 1.0 / gsd, gen);
  const int holes = int(std::round(o.holes_per_hectare * hectares * (0.5 + u(gen))));
  for (int q = 0; q < holes; ++q) {
    const double cx = u(gen) * w, cy = u(gen) * h, rad = o.hole_radius_m * (0.4 + 1.2 * u(gen)) / gsd;
    for (int j = std::max(0, int(cy - rad)); j < std::min(h, int(cy + rad) + 1); ++j)
      for (int i = std::max(0, int(cx - rad)); i < std::min(w, int(cx + rad) + 1); ++i) {
        const double d = std::hypot(i - cx, j - cy) / rad;
        if (d < 1 && shape.at<float>(j, i) > 1.6 * d * d - 0.6) z.at<float>(j, i) = NAN;
      }
  }
  Dsm out = truth;
  std::copy(z.ptr<float>(0), z.ptr<float>(0) + size_t(w) * h, out.z.begin());
  return out;
}

}  // namespace satmesh::synth
