#pragma once
// The rational function model (RFM / RPC00B), paper section 3.2.1.
//
// Pixel convention (GDAL's): (0,0) is the top-left corner of the top-left pixel; the
// RPC's integer sample s / line l is the pixel centre (s+0.5, l+0.5). All geodetic math
// is in double; heights are ellipsoidal (WGS84).
#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <string>

namespace satmesh {

// Raw RPC00B coefficients. Term order of the cubics: 1, L, P, H, LP, LH, PH, L², P², H²,
// PLH, L³, LP², LH², L²P, P³, PH², L²H, P²H, H³ (L = lon, P = lat, H = height, normalised).
struct RpcCoefficients {
  double line_off = 0, samp_off = 0, lat_off = 0, long_off = 0, height_off = 0;
  double line_scale = 1, samp_scale = 1, lat_scale = 1, long_scale = 1, height_scale = 1;
  std::array<double, 20> line_num{}, line_den{}, samp_num{}, samp_den{};
};

struct LocalizeOptions {
  int max_iterations = 30;              // Newton iterations, >= 1
  double tolerance_px = 1e-7;           // stop when the pixel residual is below this (double
                                        // lon/lat resolve ~1e-9 px at 0.3 m GSD)
};

// An RPC camera plus a pixel-space affine adjustment:
//   pixel = (rpc_pixel + 0.5 + bias - window_origin) * scale
// so crops (windows) and pyramid levels are cheap derived models of one RPC.
class RpcModel {
 public:
  // Validates (finite values, non-zero scales, non-zero denominator constant term) and
  // throws Error{kInvalidInput} naming the offending field otherwise.
  static RpcModel FromCoefficients(const RpcCoefficients& coefficients);
  // From GDAL's "RPC" metadata domain keys (LINE_OFF, ..., LINE_NUM_COEFF="c1 ... c20").
  // A missing key, unparsable or non-finite value, or zero scale throws Error naming it.
  static RpcModel FromKeyValues(const std::map<std::string, std::string>& rpc_metadata);

  const RpcCoefficients& coefficients() const { return coefficients_; }
  // GDAL "RPC" metadata domain keys for the raw coefficients (to write into a GeoTIFF).
  std::map<std::string, std::string> ToKeyValues() const;

  // (col, row) of a geodetic point (lon, lat in degrees, h in metres).
  Eigen::Vector2d PixelFromGeo(const Eigen::Vector3d& lon_lat_h) const;
  // Same, with the 2x3 Jacobian d(col,row)/d(lon,lat,h) (analytic, quotient rule).
  Eigen::Vector2d PixelFromGeo(const Eigen::Vector3d& lon_lat_h,
                               Eigen::Matrix<double, 2, 3>* pixel_from_geo_jacobian) const;

  // (lon, lat) of pixel (col, row) at height h, by Newton iteration on the analytic
  // Jacobian. std::nullopt if it does not converge (or leaves the RPC's valid domain).
  std::optional<Eigen::Vector2d> LocalizeLonLat(const Eigen::Vector2d& col_row, double h,
                                                const LocalizeOptions& options = {}) const;

  // Derived models. The bias is a shift (d_col, d_row) in full-resolution pixels added
  // to the RPC's prediction (it replaces any earlier bias).
  RpcModel WithBias(const Eigen::Vector2d& bias_col_row) const;
  // Pixel coordinates relative to a window whose top-left corner is at (col0, row0) of
  // the current model's pixel grid.
  RpcModel Cropped(const Eigen::Vector2d& window_origin_col_row) const;
  // Pixel coordinates at pyramid level `level` of the current model: divided by 2^level.
  RpcModel AtLevel(int level) const;

  Eigen::Vector2d bias() const { return bias_; }
  Eigen::Vector2d window_origin() const { return window_origin_; }  // full-res pixels
  double pixel_scale() const { return scale_; }

 private:
  RpcCoefficients coefficients_;
  Eigen::Vector2d bias_{0, 0};           // full-resolution pixels (col, row)
  Eigen::Vector2d window_origin_{0, 0};  // full-resolution pixels (col, row)
  double scale_ = 1.0;                   // pixels of this model per full-resolution pixel
};

}  // namespace satmesh
