#include "core/rpc/pinhole_fit.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/common/error.h"

namespace satmesh {
namespace {

using Matrix34d = Eigen::Matrix<double, 3, 4>;
using Vector10d = Eigen::Matrix<double, 10, 1>;

struct Sample {
  Eigen::Vector3d local;
  Eigen::Vector2d pixel;
};

// n_xy x n_xy x n_z nodes over the box, shifted by `shift` steps (0 or 0.5); a shifted
// grid has one node fewer per axis so that it stays inside the box.
std::vector<Eigen::Vector3d> Grid(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int n_xy,
                                  int n_z, double shift) {
  const int m_xy = shift > 0 ? n_xy - 1 : n_xy, m_z = shift > 0 ? n_z - 1 : n_z;
  const Eigen::Vector3d step =
      (hi - lo).cwiseQuotient(Eigen::Vector3d(n_xy - 1, n_xy - 1, n_z - 1));
  std::vector<Eigen::Vector3d> out;
  out.reserve(static_cast<size_t>(m_xy) * m_xy * m_z);
  for (int k = 0; k < m_z; ++k)
    for (int j = 0; j < m_xy; ++j)
      for (int i = 0; i < m_xy; ++i)
        out.push_back(lo + Eigen::Vector3d(i + shift, j + shift, k + shift).cwiseProduct(step));
  return out;
}

std::vector<Sample> Project(
    const std::function<Eigen::Vector2d(const Eigen::Vector3d&)>& pixel_from_local,
    const std::vector<Eigen::Vector3d>& points) {
  std::vector<Sample> samples;
  samples.reserve(points.size());
  for (const auto& p : points) {
    const Eigen::Vector2d px = pixel_from_local(p);
    SATMESH_CHECK(px.allFinite(), ErrorCode::kInvalidArgument,
                  "FitPinhole: the camera gives a non-finite pixel inside the box");
    samples.push_back({p, px});
  }
  return samples;
}

// Hartley's normalisation: centroid to the origin, mean distance sqrt(dim).
template <int Dim>
Eigen::Matrix<double, Dim + 1, Dim + 1> Normalisation(
    const std::vector<Eigen::Matrix<double, Dim, 1>>& points) {
  Eigen::Matrix<double, Dim, 1> mean = Eigen::Matrix<double, Dim, 1>::Zero();
  for (const auto& p : points) mean += p;
  mean /= double(points.size());
  double spread = 0;
  for (const auto& p : points) spread += (p - mean).norm();
  const double scale = std::sqrt(double(Dim)) * double(points.size()) / std::max(spread, 1e-300);
  Eigen::Matrix<double, Dim + 1, Dim + 1> t = Eigen::Matrix<double, Dim + 1, Dim + 1>::Identity();
  t.template topLeftCorner<Dim, Dim>() *= scale;
  t.template topRightCorner<Dim, 1>() = -scale * mean;
  return t;
}

// The 3x4 projection minimising the algebraic error on normalised points.
Matrix34d Dlt(const std::vector<Sample>& samples) {
  std::vector<Eigen::Vector3d> xyz;
  std::vector<Eigen::Vector2d> uv;
  for (const auto& s : samples) xyz.push_back(s.local), uv.push_back(s.pixel);
  const Eigen::Matrix4d t3 = Normalisation<3>(xyz);
  const Eigen::Matrix3d t2 = Normalisation<2>(uv);
  Eigen::MatrixXd a(2 * samples.size(), 12);
  for (size_t i = 0; i < samples.size(); ++i) {
    const Eigen::RowVector4d x = (t3 * xyz[i].homogeneous()).transpose();
    const Eigen::Vector2d u = (t2 * uv[i].homogeneous()).head<2>();
    a.row(2 * i) << x, Eigen::RowVector4d::Zero(), -u.x() * x;
    a.row(2 * i + 1) << Eigen::RowVector4d::Zero(), x, -u.y() * x;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinV);
  const Eigen::Matrix<double, 12, 1> p = svd.matrixV().col(11);
  Matrix34d normalised;
  normalised << p.segment<4>(0).transpose(), p.segment<4>(4).transpose(),
      p.segment<4>(8).transpose();
  return t2.inverse() * normalised * t3;
}

// P = K [R | t], K upper triangular with a positive diagonal and K(2, 2) = 1, det R = 1.
void Decompose(Matrix34d p, Eigen::Matrix3d* k, Eigen::Matrix3d* r, Eigen::Vector3d* t) {
  if (p.leftCols<3>().determinant() < 0) p = -p;
  Eigen::Matrix3d flip;
  flip << 0, 0, 1, 0, 1, 0, 1, 0, 0;
  // RQ through QR: (flip M)^T = Q U  =>  M = (flip U^T flip) (flip Q^T).
  const Eigen::HouseholderQR<Eigen::Matrix3d> qr((flip * p.leftCols<3>()).transpose());
  const Eigen::Matrix3d q = qr.householderQ();
  const Eigen::Matrix3d u = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::Matrix3d kk = flip * u.transpose() * flip, rr = flip * q.transpose();
  const Eigen::Vector3d signs = kk.diagonal().cwiseSign();
  kk = kk * signs.asDiagonal();
  rr = signs.asDiagonal() * rr;
  *t = kk.inverse() * p.col(3);
  *k = kk / kk(2, 2);
  *r = rr;
}

// Residuals (u, v per sample) and their Jacobian with respect to
// (fx, fy, cx, cy, w (left rotation increment, 3), t (3)).
double Linearise(const PinholeCamera& c, const std::vector<Sample>& samples,
                 Eigen::Matrix<double, 10, 10>* jtj, Vector10d* jtr) {
  jtj->setZero();
  jtr->setZero();
  double cost = 0;
  for (const auto& s : samples) {
    const Eigen::Vector3d rx = c.cam_from_local_rotation * s.local;
    const Eigen::Vector3d x = rx + c.cam_from_local_translation;
    const double iz = 1.0 / x.z();
    const Eigen::Vector2d r(c.fx * x.x() * iz + c.cx - s.pixel.x(),
                            c.fy * x.y() * iz + c.cy - s.pixel.y());
    Eigen::Matrix<double, 2, 3> d_x;  // d(u, v) / d(camera point)
    d_x << c.fx * iz, 0, -c.fx * x.x() * iz * iz, 0, c.fy * iz, -c.fy * x.y() * iz * iz;
    Eigen::Matrix3d skew_rx;
    skew_rx << 0, -rx.z(), rx.y(), rx.z(), 0, -rx.x(), -rx.y(), rx.x(), 0;
    Eigen::Matrix<double, 2, 10> j = Eigen::Matrix<double, 2, 10>::Zero();
    j(0, 0) = x.x() * iz;
    j(1, 1) = x.y() * iz;
    j(0, 2) = 1;
    j(1, 3) = 1;
    j.block<2, 3>(0, 4) = -d_x * skew_rx;
    j.block<2, 3>(0, 7) = d_x;
    *jtj += j.transpose() * j;
    *jtr += j.transpose() * r;
    cost += r.squaredNorm();
  }
  return cost;
}

PinholeCamera Updated(const PinholeCamera& c, const Vector10d& delta) {
  PinholeCamera out = c;
  out.fx += delta[0], out.fy += delta[1], out.cx += delta[2], out.cy += delta[3];
  const Eigen::Vector3d w = delta.segment<3>(4);
  const Eigen::Matrix3d dr = w.norm() > 0
                                 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                                 : Eigen::Matrix3d::Identity();
  out.cam_from_local_rotation = dr * c.cam_from_local_rotation;
  // d(camera point) = w x (R X) + dt, as Linearise's Jacobian has it.
  out.cam_from_local_translation = c.cam_from_local_translation + delta.segment<3>(7);
  return out;
}

double Cost(const PinholeCamera& c, const std::vector<Sample>& samples) {
  double cost = 0;
  for (const auto& s : samples) cost += (c.PixelFromLocal(s.local) - s.pixel).squaredNorm();
  return cost;
}

// Levenberg-Marquardt with Marquardt's diagonal damping, solved on the Jacobi-scaled
// normal equations (focal length and distance are nearly degenerate for a far camera).
int LevenbergMarquardt(const std::vector<Sample>& samples, int max_iterations,
                       PinholeCamera* camera) {
  double lambda = 1e-3;
  int iterations = 0;
  for (; iterations < max_iterations; ++iterations) {
    Eigen::Matrix<double, 10, 10> jtj;
    Vector10d jtr;
    const double cost = Linearise(*camera, samples, &jtj, &jtr);
    const Vector10d scale = jtj.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Eigen::Matrix<double, 10, 10> a = scale.asDiagonal() * jtj * scale.asDiagonal();
    const Vector10d b = -scale.cwiseProduct(jtr);
    bool improved = false;
    for (int attempt = 0; attempt < 12 && !improved; ++attempt) {
      Eigen::Matrix<double, 10, 10> damped = a;
      damped.diagonal().array() += lambda;
      const Vector10d delta = scale.cwiseProduct(damped.ldlt().solve(b));
      const PinholeCamera trial = Updated(*camera, delta);
      const double trial_cost = Cost(trial, samples);
      if (std::isfinite(trial_cost) && trial_cost < cost) {
        *camera = trial;
        lambda = std::max(lambda * 0.2, 1e-12);
        improved = true;
        if (cost - trial_cost < 1e-12 * cost) return iterations + 1;
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  return iterations;
}

void Errors(const PinholeCamera& c, const std::vector<Sample>& samples, double* rms, double* max) {
  double sum = 0;
  *max = 0;
  for (const auto& s : samples) {
    const double e = (c.PixelFromLocal(s.local) - s.pixel).norm();
    sum += e * e;
    *max = std::max(*max, e);
  }
  if (rms) *rms = std::sqrt(sum / double(samples.size()));
}

}  // namespace

std::string PinholeFitOptions::Check() const {
  if (grid_xy < 2 || grid_xy > 200) return "grid_xy must be in [2, 200]";
  if (grid_z < 2 || grid_z > 100) return "grid_z must be in [2, 100]";
  if (max_iterations < 0 || max_iterations > 10000) return "max_iterations must be in [0, 10000]";
  return "";
}

Eigen::Vector2d PinholeCamera::PixelFromLocal(const Eigen::Vector3d& local) const {
  const Eigen::Vector3d x = cam_from_local_rotation * local + cam_from_local_translation;
  return {fx * x.x() / x.z() + cx, fy * x.y() / x.z() + cy};
}

Eigen::Vector3d PinholeCamera::CenterInLocal() const {
  return -cam_from_local_rotation.transpose() * cam_from_local_translation;
}

PinholeFitResult FitPinhole(
    const std::function<Eigen::Vector2d(const Eigen::Vector3d& local)>& pixel_from_local,
    const Eigen::Vector3d& min_local, const Eigen::Vector3d& max_local,
    const PinholeFitOptions& options) {
  const std::string msg = options.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, "FitPinhole: " + msg);
  SATMESH_CHECK((max_local - min_local).minCoeff() > 0, ErrorCode::kInvalidArgument,
                "FitPinhole: the box is empty along an axis");
  const std::vector<Sample> samples =
      Project(pixel_from_local, Grid(min_local, max_local, options.grid_xy, options.grid_z, 0));

  // 1. DLT and its decomposition.
  const Matrix34d p = Dlt(samples);
  Eigen::Matrix3d k, r;
  Eigen::Vector3d t;
  Decompose(p, &k, &r, &t);
  PinholeFitResult result;
  result.dlt_skew_px = k(0, 1);
  {
    double sum = 0;
    for (const auto& s : samples)
      sum += ((p * s.local.homogeneous()).hnormalized() - s.pixel).squaredNorm();
    result.dlt_rms_px = std::sqrt(sum / double(samples.size()));
  }

  // 2. Zero skew: s * y / z absorbed into cx at the samples' mean y / z.
  PinholeCamera& c = result.camera;
  c.fx = k(0, 0), c.fy = k(1, 1), c.cx = k(0, 2), c.cy = k(1, 2);
  c.cam_from_local_rotation = r;
  c.cam_from_local_translation = t;
  double mean_y_over_z = 0;
  for (const auto& s : samples) {
    const Eigen::Vector3d x = r * s.local + t;
    SATMESH_CHECK(x.z() > 0, ErrorCode::kInvalidInput,
                  "FitPinhole: the box projects from behind the fitted camera");
    mean_y_over_z += x.y() / x.z();
  }
  c.cx += k(0, 1) * mean_y_over_z / double(samples.size());

  // 3. Levenberg-Marquardt on the zero-skew pinhole.
  result.iterations = LevenbergMarquardt(samples, options.max_iterations, &c);

  Errors(c, samples, &result.rms_px, &result.max_px);
  const std::vector<Sample> shifted =
      Project(pixel_from_local, Grid(min_local, max_local, options.grid_xy, options.grid_z, 0.5));
  Errors(c, shifted, nullptr, &result.max_px_half_step);
  return result;
}

}  // namespace satmesh
