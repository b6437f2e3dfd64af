#pragma once
// A single-band float image and the operations the refinement needs. Pixel coordinates
// follow GDAL: pixel (i, j) covers [i, i+1) x [j, j+1); its centre is (i+0.5, j+0.5).
#include <cstddef>
#include <string>
#include <vector>

namespace satmesh {

struct ImageF {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;  // row-major, width*height

  ImageF() = default;
  ImageF(int w, int h, float value = 0.f) : width(w), height(h), pixels(size_t(w) * h, value) {}
  bool empty() const { return pixels.empty(); }
  float& at(int col, int row) { return pixels[size_t(row) * width + col]; }
  float at(int col, int row) const { return pixels[size_t(row) * width + col]; }
};

// Bilinear sample at continuous (x, y) in GDAL pixel convention. Returns false (and
// leaves outputs untouched) when the 2x2 support leaves the image.
bool SampleBilinear(const ImageF& image, double x, double y, float* value);
// Value and analytic gradient (d/dx, d/dy) of the bilinear interpolant of `image`.
bool SampleBilinearWithGradient(const ImageF& image, double x, double y, float* value,
                                float* d_dx, float* d_dy);

// Central-difference gradients (per pixel unit), same size as the input.
void ComputeGradients(const ImageF& image, ImageF* d_dx, ImageF* d_dy);

// Gaussian pyramid of `levels` images (levels >= 1, else Error{kInvalidArgument}):
// level 0 is the input, level l has size ceil(size / 2^l); level l's
// pixel grid is level 0's scaled by 1/2^l (corner-origin), matching RpcModel::AtLevel.
// Each step: Gaussian blur (sigma 1 px), then 2x2 box averaging (odd sizes edge-padded).
std::vector<ImageF> GaussianPyramid(const ImageF& image, int levels);

struct RadiometryOptions {
  double low_percentile = 0.5;    // clipped low end, in percent, in [0, 50)
  double high_percentile = 99.5;  // clipped high end, in percent, in (50, 100]

  std::string Check() const;  // "" or a message naming the bad field
};
// Maps the image affinely so that the given percentiles become 0 and 1 (values beyond
// are kept, not clipped): 11-16 bit images become comparable unit-range images.
// Non-finite pixels are ignored for the percentiles. A constant image is only shifted.
// Throws Error{kInvalidArgument} when options.Check() fails.
// Standard deviation of the image's noise (after Immerkær 1996, "Fast noise variance
// estimation"): the response to the Laplacian-difference mask [1 -2 1; -2 4 -2; 1 -2 1]
// cancels structure up to second order and has std 6 sigma on white noise; its median
// absolute value / (0.6745 x 6), robust to the edges and texture of part of the image.
// 0 for images under 3x3.
double NoiseSigma(const ImageF& image);

ImageF NormalizeRadiometry(const ImageF& image, const RadiometryOptions& options = {});

}  // namespace satmesh
