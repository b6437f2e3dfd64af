#pragma once
// Fitting an RPC00B to an exact camera (terrain-independent fit), e.g. the pushbroom
// cameras of the synthetic scene generator.
#include <Eigen/Core>
#include <functional>
#include <string>

#include "core/rpc/rpc_model.h"

namespace satmesh {

struct RpcFitOptions {
  int grid_xy = 15;              // samples per lon and per lat axis of the fit grid, [3, 200]
  int grid_h = 9;                // samples along the height axis, [2, 100]
  double regularization = 1e-12; // Tikhonov weight on the normalised coefficients, >= 0
  int reweight_iterations = 6;   // denominator reweighting rounds (Tao & Hu 2001), [0, 50]
  std::string Check() const;     // "" when valid, else a message naming the field
};

struct RpcFitResult {
  RpcModel model;
  double rms_px = 0;            // RMS of |pixel error| on the fit grid
  double max_px = 0;            // max |pixel error| on the fit grid
  double max_px_half_step = 0;  // max |pixel error| on the grid shifted by half a step
};

// Fits an RPC00B to pixel_from_geo, which maps (lon deg, lat deg, h m) to GDAL-convention
// (col, row), over the box [min, max]. Throws Error{kInvalidArgument} on invalid options,
// an empty box or a non-finite camera output.
RpcFitResult FitRpc(const std::function<Eigen::Vector2d(const Eigen::Vector3d& lon_lat_h)>&
                        pixel_from_geo,
                    const Eigen::Vector3d& min_lon_lat_h, const Eigen::Vector3d& max_lon_lat_h,
                    const RpcFitOptions& options = {});

}  // namespace satmesh
