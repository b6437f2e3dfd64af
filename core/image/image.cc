#include "core/image/image.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/common/error.h"

namespace satmesh {
namespace {

// Bilinear support of continuous (x, y): top-left sample (i0, j0), right/down
// neighbours (i1, j1) and fractions. False when (x, y) lies outside the pixel centres.
struct Support {
  int i0, j0, i1, j1;
  double fx, fy;
};

bool FindSupport(const ImageF& image, double x, double y, Support* s) {
  const double u = x - 0.5, v = y - 0.5;  // centre-origin pixel coordinates
  if (!(u >= 0.0 && v >= 0.0 && u <= image.width - 1 && v <= image.height - 1)) return false;
  s->i0 = std::min(int(u), std::max(image.width - 2, 0));
  s->j0 = std::min(int(v), std::max(image.height - 2, 0));
  s->i1 = std::min(s->i0 + 1, image.width - 1);
  s->j1 = std::min(s->j0 + 1, image.height - 1);
  s->fx = u - s->i0;
  s->fy = v - s->j0;
  return true;
}

cv::Mat AsMat(const ImageF& image) {
  return cv::Mat(image.height, image.width, CV_32F, const_cast<float*>(image.pixels.data()));
}

ImageF FromMat(const cv::Mat& mat) {
  ImageF image(mat.cols, mat.rows);
  cv::Mat view = AsMat(image);
  mat.copyTo(view);
  return image;
}

// One pyramid step: Gaussian blur, pad to even size, 2x2 box average. The 2x2 box keeps
// the corner-origin grid exact: new pixel i covers old pixels [2i, 2i+2).
ImageF HalveImage(const ImageF& image) {
  if (image.empty()) return image;
  cv::Mat blurred;
  cv::GaussianBlur(AsMat(image), blurred, cv::Size(0, 0), /*sigmaX=*/1.0, /*sigmaY=*/1.0,
                   cv::BORDER_REFLECT);
  cv::copyMakeBorder(blurred, blurred, 0, image.height % 2, 0, image.width % 2,
                     cv::BORDER_REPLICATE);
  cv::Mat half;
  cv::resize(blurred, half, cv::Size(blurred.cols / 2, blurred.rows / 2), 0, 0,
             cv::INTER_AREA);
  return FromMat(half);
}

// p-th percentile (p in [0, 100]) with linear interpolation between order statistics.
double Percentile(std::vector<float>& values, double p) {
  const double rank = p / 100.0 * double(values.size() - 1);
  const size_t k = size_t(rank);
  std::nth_element(values.begin(), values.begin() + k, values.end());
  const double lo = values[k];
  if (k + 1 >= values.size()) return lo;
  const double hi = *std::min_element(values.begin() + k + 1, values.end());
  return lo + (rank - double(k)) * (hi - lo);
}

}  // namespace

bool SampleBilinear(const ImageF& image, double x, double y, float* value) {
  Support s;
  if (image.empty() || !FindSupport(image, x, y, &s)) return false;
  const double top = (1 - s.fx) * image.at(s.i0, s.j0) + s.fx * image.at(s.i1, s.j0);
  const double bottom = (1 - s.fx) * image.at(s.i0, s.j1) + s.fx * image.at(s.i1, s.j1);
  *value = float((1 - s.fy) * top + s.fy * bottom);
  return true;
}

bool SampleBilinearWithGradient(const ImageF& image, double x, double y, float* value,
                                float* d_dx, float* d_dy) {
  Support s;
  if (image.empty() || !FindSupport(image, x, y, &s)) return false;
  const double p00 = image.at(s.i0, s.j0), p10 = image.at(s.i1, s.j0);
  const double p01 = image.at(s.i0, s.j1), p11 = image.at(s.i1, s.j1);
  const double top = (1 - s.fx) * p00 + s.fx * p10;
  const double bottom = (1 - s.fx) * p01 + s.fx * p11;
  *value = float((1 - s.fy) * top + s.fy * bottom);
  *d_dx = float((1 - s.fy) * (p10 - p00) + s.fy * (p11 - p01));
  *d_dy = float(bottom - top);
  return true;
}

void ComputeGradients(const ImageF& image, ImageF* d_dx, ImageF* d_dy) {
  *d_dx = ImageF(image.width, image.height);
  *d_dy = ImageF(image.width, image.height);
  if (image.empty()) return;
  cv::Mat gx = AsMat(*d_dx), gy = AsMat(*d_dy);
  // ksize 1: the plain [-1 0 1] kernel, halved; replicated borders give half a
  // one-sided difference there, which is corrected below.
  cv::Sobel(AsMat(image), gx, CV_32F, 1, 0, 1, 0.5, 0, cv::BORDER_REPLICATE);
  cv::Sobel(AsMat(image), gy, CV_32F, 0, 1, 1, 0.5, 0, cv::BORDER_REPLICATE);
  const int w = image.width, h = image.height;
  if (w >= 2) {
    for (int r = 0; r < h; ++r) {
      d_dx->at(0, r) = image.at(1, r) - image.at(0, r);
      d_dx->at(w - 1, r) = image.at(w - 1, r) - image.at(w - 2, r);
    }
  }
  if (h >= 2) {
    for (int c = 0; c < w; ++c) {
      d_dy->at(c, 0) = image.at(c, 1) - image.at(c, 0);
      d_dy->at(c, h - 1) = image.at(c, h - 1) - image.at(c, h - 2);
    }
  }
}

std::vector<ImageF> GaussianPyramid(const ImageF& image, int levels) {
  SATMESH_CHECK(levels >= 1, ErrorCode::kInvalidArgument,
                "GaussianPyramid: levels must be >= 1, got " + std::to_string(levels));
  std::vector<ImageF> pyramid{image};
  for (int l = 1; l < levels; ++l) pyramid.push_back(HalveImage(pyramid.back()));
  return pyramid;
}

std::string RadiometryOptions::Check() const {
  if (!(low_percentile >= 0 && low_percentile < 50))
    return "low_percentile must be in [0, 50), got " + std::to_string(low_percentile);
  if (!(high_percentile > 50 && high_percentile <= 100))
    return "high_percentile must be in (50, 100], got " + std::to_string(high_percentile);
  return "";
}

double NoiseSigma(const ImageF& image) {
  const int w = image.width, h = image.height;
  if (w < 3 || h < 3) return 0.0;
  const cv::Mat src(h, w, CV_32F, const_cast<float*>(image.pixels.data()));
  const cv::Matx33f mask(1, -2, 1, -2, 4, -2, 1, -2, 1);
  cv::Mat response;
  cv::filter2D(src, response, CV_32F, mask);
  std::vector<float> magnitude;
  magnitude.reserve(size_t(w - 2) * (h - 2));
  for (int r = 1; r + 1 < h; ++r)
    for (int c = 1; c + 1 < w; ++c) magnitude.push_back(std::abs(response.at<float>(r, c)));
  auto median = magnitude.begin() + magnitude.size() / 2;
  std::nth_element(magnitude.begin(), median, magnitude.end());
  return *median / (0.6745 * 6.0);  // the mask's response to noise has std 6 sigma
}

ImageF NormalizeRadiometry(const ImageF& image, const RadiometryOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "RadiometryOptions: " + problem);
  std::vector<float> finite;
  finite.reserve(image.pixels.size());
  for (float v : image.pixels)
    if (std::isfinite(v)) finite.push_back(v);
  if (finite.empty()) return image;
  const double lo = Percentile(finite, options.low_percentile);
  const double hi = Percentile(finite, options.high_percentile);
  const double scale = hi - lo > 1e-12 * std::max(1.0, std::abs(hi)) ? 1.0 / (hi - lo) : 1.0;
  ImageF out(image.width, image.height);
  for (size_t i = 0; i < image.pixels.size(); ++i)
    out.pixels[i] = float((image.pixels[i] - lo) * scale);
  return out;
}

}  // namespace satmesh
