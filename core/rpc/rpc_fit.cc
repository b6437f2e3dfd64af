#include "core/rpc/rpc_fit.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/common/error.h"

namespace satmesh {
namespace {

using Coeffs = std::array<double, 20>;

struct Sample {
  Eigen::Vector3d lon_lat_h;
  Eigen::Vector2d col_row;
};

Eigen::Matrix<double, 20, 1> Monomials(const Eigen::Vector3d& n) {
  const double l = n.x(), p = n.y(), h = n.z();
  Eigen::Matrix<double, 20, 1> t;
  t << 1, l, p, h, l * p, l * h, p * h, l * l, p * p, h * h, p * l * h, l * l * l, l * p * p,
      l * h * h, l * l * p, p * p * p, p * h * h, l * l * h, p * p * h, h * h * h;
  return t;
}

// Grid over the box with n_xy x n_xy x n_h nodes, shifted by `shift` steps (0 or 0.5);
// a shifted grid has one node fewer per axis so it stays inside the box.
std::vector<Eigen::Vector3d> Grid(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n_xy,
                                  int n_h, double shift) {
  const int m_xy = shift > 0 ? n_xy - 1 : n_xy, m_h = shift > 0 ? n_h - 1 : n_h;
  const Eigen::Vector3d step = (hi - lo).cwiseQuotient(Eigen::Vector3d(n_xy - 1, n_xy - 1, n_h - 1));
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<size_t>(m_xy) * m_xy * m_h);
  for (int k = 0; k < m_h; ++k)
    for (int j = 0; j < m_xy; ++j)
      for (int i = 0; i < m_xy; ++i)
        out.push_back(lo + Eigen::Vector3d(i + shift, j + shift, k + shift).cwiseProduct(step));
  return out;
}

// Fits r ~ (m . num) / (m . den), den[0] = 1, by reweighted linearised least squares.
void FitRatio(const Eigen::MatrixXd& mono, const Eigen::VectorXd& r, const RpcFitOptions& opt,
              Coeffs* num, Coeffs* den) {
  const Eigen::Index n = mono.rows();
  Eigen::VectorXd weight = Eigen::VectorXd::Ones(n);
  Eigen::MatrixXd a(n + 39, 39);
  Eigen::VectorXd b(n + 39);
  Eigen::VectorXd x(39);
  for (int round = 0; round <= opt.reweight_iterations; ++round) {
    a.setZero();
    b.setZero();
    for (Eigen::Index i = 0; i < n; ++i) {
      a.row(i).head<20>() = weight(i) * mono.row(i);
      a.row(i).tail<19>() = -weight(i) * r(i) * mono.row(i).tail<19>();
      b(i) = weight(i) * r(i);
    }
    const double ridge = std::sqrt(opt.regularization * static_cast<double>(n));
    a.bottomRows(39).diagonal().setConstant(ridge);
    x = a.colPivHouseholderQr().solve(b);
    // Tao & Hu: weight each equation by 1 / denominator so it measures the true residual.
    Eigen::VectorXd den_values = mono.col(0) + mono.rightCols<19>() * x.tail<19>();
    weight = den_values.cwiseAbs().cwiseMax(1e-12).cwiseInverse();
  }
  for (int i = 0; i < 20; ++i) (*num)[i] = x(i);
  (*den)[0] = 1.0;
  for (int i = 1; i < 20; ++i) (*den)[i] = x(19 + i);
}

}  // namespace

std::string RpcFitOptions::Check() const {
  if (grid_xy < 3 || grid_xy > 200) return "grid_xy must be in [3, 200], got " + std::to_string(grid_xy);
  if (grid_h < 2 || grid_h > 100) return "grid_h must be in [2, 100], got " + std::to_string(grid_h);
  if (!(regularization >= 0) || !std::isfinite(regularization))
    return "regularization must be finite and >= 0, got " + std::to_string(regularization);
  if (reweight_iterations < 0 || reweight_iterations > 50)
    return "reweight_iterations must be in [0, 50], got " + std::to_string(reweight_iterations);
  return "";
}

RpcFitResult FitRpc(const std::function<Eigen::Vector2d(const Eigen::Vector3d&)>& pixel_from_geo,
                    const Eigen::Vector3d& min_lon_lat_h, const Eigen::Vector3d& max_lon_lat_h,
                    const RpcFitOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "RpcFitOptions: " + problem);
  SATMESH_CHECK((max_lon_lat_h - min_lon_lat_h).minCoeff() > 0 && min_lon_lat_h.allFinite() &&
                    max_lon_lat_h.allFinite(),
                ErrorCode::kInvalidArgument, "FitRpc: the lon/lat/h box must have min < max");

  // 1. Sample the camera on the fit grid.
  std::vector<Sample> samples;
  for (const Eigen::Vector3d& g :
       Grid(min_lon_lat_h, max_lon_lat_h, options.grid_xy, options.grid_h, 0.0)) {
    const Eigen::Vector2d px = pixel_from_geo(g);
    SATMESH_CHECK(px.allFinite(), ErrorCode::kInvalidArgument,
                  "FitRpc: the camera returned a non-finite pixel");
    samples.push_back({g, px});
  }

  // 2. Normalisation: ground from the box, image from the sampled pixel range.
  RpcCoefficients c;
  const Eigen::Vector3d geo_off = 0.5 * (min_lon_lat_h + max_lon_lat_h);
  const Eigen::Vector3d geo_scale = 0.5 * (max_lon_lat_h - min_lon_lat_h);
  c.long_off = geo_off.x(), c.lat_off = geo_off.y(), c.height_off = geo_off.z();
  c.long_scale = geo_scale.x(), c.lat_scale = geo_scale.y(), c.height_scale = geo_scale.z();
  Eigen::Vector2d px_min = samples[0].col_row, px_max = samples[0].col_row;
  for (const Sample& s : samples) {
    px_min = px_min.cwiseMin(s.col_row);
    px_max = px_max.cwiseMax(s.col_row);
  }
  // RPC sample/line = GDAL col/row - 0.5 (pixel centre convention).
  const Eigen::Vector2d img_off = 0.5 * (px_min + px_max) - Eigen::Vector2d(0.5, 0.5);
  const Eigen::Vector2d img_scale = (0.5 * (px_max - px_min)).cwiseMax(1.0);
  c.samp_off = img_off.x(), c.line_off = img_off.y();
  c.samp_scale = img_scale.x(), c.line_scale = img_scale.y();

  // 3. Linearised fits of sample and line.
  const Eigen::Index n = static_cast<Eigen::Index>(samples.size());
  Eigen::MatrixXd mono(n, 20);
  Eigen::VectorXd samp(n), line(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Sample& s = samples[i];
    mono.row(i) = Monomials((s.lon_lat_h - geo_off).cwiseQuotient(geo_scale)).transpose();
    samp(i) = (s.col_row.x() - 0.5 - c.samp_off) / c.samp_scale;
    line(i) = (s.col_row.y() - 0.5 - c.line_off) / c.line_scale;
  }
  FitRatio(mono, samp, options, &c.samp_num, &c.samp_den);
  FitRatio(mono, line, options, &c.line_num, &c.line_den);

  // 4. Errors on the fit grid and on the half-step shifted grid.
  RpcFitResult result{RpcModel::FromCoefficients(c)};
  double sum_sq = 0;
  for (const Sample& s : samples) {
    const double e = (result.model.PixelFromGeo(s.lon_lat_h) - s.col_row).norm();
    sum_sq += e * e;
    result.max_px = std::max(result.max_px, e);
  }
  result.rms_px = std::sqrt(sum_sq / static_cast<double>(n));
  for (const Eigen::Vector3d& g :
       Grid(min_lon_lat_h, max_lon_lat_h, options.grid_xy, options.grid_h, 0.5)) {
    const double e = (result.model.PixelFromGeo(g) - pixel_from_geo(g)).norm();
    result.max_px_half_step = std::max(result.max_px_half_step, e);
  }
  return result;
}

}  // namespace satmesh
