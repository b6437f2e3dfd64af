#pragma once
// A pinhole camera fitted to an exact camera (an RPC through a local frame) over a 3D box,
// for handing satellite views to frame-camera tools (COLMAP, OpenMVS), as
// SatelliteSurfaceReconstruction does. Over a few hundred metres a satellite view is very
// close to affine, so a pinhole with a distant centre reproduces it within hundredths of
// a pixel (tests/core/rpc/pinhole_fit_test.cc).
//
// Steps: a grid of points in the box and their pixels; a normalised DLT (Hartley) of the
// 3x4 projection; its RQ decomposition into K [R | t]; the skew set to zero (absorbed into
// the principal point at the box centre); Levenberg-Marquardt on fx, fy, cx, cy, R, t.
// Pixel convention: whatever the camera gives; satmesh's RPCs give GDAL's, (0, 0) the
// top-left corner of the top-left pixel, which is COLMAP's too.
#include <Eigen/Core>
#include <functional>
#include <string>

namespace satmesh {

struct PinholeFitOptions {
  int grid_xy = 11;  // samples per x and per y axis of the box, [2, 200]
  int grid_z = 5;    // samples along z, [2, 100]
  int max_iterations =
      1000;  // Levenberg-Marquardt iterations, [0, 10000] (0: DLT only, skew zeroed)
  std::string Check() const;  // "" when valid, else a message naming the field
};

// pixel = (fx * x / z + cx, fy * y / z + cy) with (x, y, z) = R * local + t.
struct PinholeCamera {
  double fx = 1, fy = 1, cx = 0, cy = 0;  // pixels
  Eigen::Matrix3d cam_from_local_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d cam_from_local_translation = Eigen::Vector3d::Zero();

  Eigen::Vector2d PixelFromLocal(const Eigen::Vector3d& local) const;
  Eigen::Vector3d CenterInLocal() const;  // -R^T t
};

struct PinholeFitResult {
  PinholeCamera camera;
  double dlt_skew_px = 0;       // K(0, 1) of the unconstrained DLT (0 for a true pinhole)
  double dlt_rms_px = 0;        // RMS error of the unconstrained DLT on the fit grid
  double rms_px = 0;            // RMS of |pixel error| of `camera` on the fit grid
  double max_px = 0;            // max |pixel error| on the fit grid
  double max_px_half_step = 0;  // max |pixel error| on the grid shifted by half a step
  int iterations = 0;           // Levenberg-Marquardt iterations run
};

// Fits a zero-skew pinhole to pixel_from_local over the box [min_local, max_local].
// Throws Error{kInvalidArgument} on invalid options, a box that is empty along any axis
// or a non-finite camera output, and Error{kInvalidInput} when the points project from
// behind the fitted camera (no pinhole can explain them).
PinholeFitResult FitPinhole(
    const std::function<Eigen::Vector2d(const Eigen::Vector3d& local)>& pixel_from_local,
    const Eigen::Vector3d& min_local, const Eigen::Vector3d& max_local,
    const PinholeFitOptions& options = {});

}  // namespace satmesh
