#pragma once
// One 3x3 quadratic step of a 2D search for a maximum (the bias estimation's per-view
// shifts and the block's datum on the surface). Objective: Evaluate(vector of points) ->
// values (may evaluate them in parallel and cache), operator()(point) -> value.
#include <Eigen/Core>
#include <Eigen/LU>

#include <vector>

namespace satmesh {

// One 3x3 step at spacing h: a quadratic fit (least squares on the 9 values); its maximum
// if the fit is concave (clamped to +-h per axis), else the best of the 9.
template <typename Objective>
Eigen::Vector2d QuadraticStep(Objective& f, const Eigen::Vector2d& d, double h) {
  std::vector<Eigen::Vector2d> points;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) points.push_back(d + h * Eigen::Vector2d(i - 1, j - 1));
  const std::vector<double> values = f.Evaluate(points);
  double v[3][3];
  Eigen::Vector2d best = d;
  double best_value = -1e30;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      v[j][i] = values[3 * j + i];
      if (v[j][i] > best_value) best_value = v[j][i], best = points[3 * j + i];
    }
  }
  double gx = 0, gy = 0, hxx = 0, hyy = 0;
  for (int k = 0; k < 3; ++k) {
    gx += (v[k][2] - v[k][0]) / (6 * h);
    gy += (v[2][k] - v[0][k]) / (6 * h);
    hxx += (v[k][2] - 2 * v[k][1] + v[k][0]) / (3 * h * h);
    hyy += (v[2][k] - 2 * v[1][k] + v[0][k]) / (3 * h * h);
  }
  const double hxy = (v[2][2] - v[0][2] - v[2][0] + v[0][0]) / (4 * h * h);
  Eigen::Matrix2d hessian;
  hessian << hxx, hxy, hxy, hyy;
  if (!(hxx < 0 && hessian.determinant() > 0)) return best;
  const Eigen::Vector2d step = (-hessian.inverse() * Eigen::Vector2d(gx, gy)).cwiseMax(-h).cwiseMin(h);
  const Eigen::Vector2d candidate = d + step;
  return f(candidate) >= best_value ? candidate : best;
}

}  // namespace satmesh
