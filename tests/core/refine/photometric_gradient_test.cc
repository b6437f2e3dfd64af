#include "core/refine/photometric_gradient.h"

#include <gtest/gtest.h>

#include "core/image/image.h"
#include "core/mesh/topology.h"
#include "tests/core/refine/plane_scene.h"

namespace satmesh {
namespace {

struct TwoViews {
  RefineInput input;
  std::vector<ViewLevel> views;
  PhotometricOptions options;
};

TwoViews MakeTwoViews(const TriangleMesh& mesh) {
  TwoViews s;
  const testing::Plane plane;
  s.input = testing::MakePlaneInput(plane, {{3, 0}, {10, 90}}, mesh, 120, 0.5);
  for (int v = 0; v < 2; ++v) {
    s.views.push_back(MakeViewLevel(v, 0, NormalizeRadiometry(s.input.views[v].image),
                                    s.input.views[v].rpc, s.input.frame,
                                    Eigen::Vector3d(-40, -40, -15), Eigen::Vector3d(40, 40, 20), 8));
  }
  s.options.visibility_tolerance_m = 1.0;
  s.options.zncc.variance_floor = 1e-4;
  return s;
}

// E = M_01 + M_10 = -Σ ZNCC, and optionally its gradient.
double Energy(TwoViews& s, const TriangleMesh& mesh, std::vector<Eigen::Vector3d>* gradient) {
  RayScene scene(mesh);
  for (auto& v : s.views) CastHitMap(scene, &v);
  const auto normals = FaceNormals(mesh);
  double e = 0;
  e -= AccumulatePhotometricGradient(s.views[0], s.views[1], mesh, normals,
                                     s.options, gradient, nullptr).sum_zncc;
  e -= AccumulatePhotometricGradient(s.views[1], s.views[0], mesh, normals,
                                     s.options, gradient, nullptr).sum_zncc;
  return e;
}

TEST(AccumulatePhotometricGradient, MatchesFiniteDifferencesOfTheEnergy) {
  // A plane mesh 0.4 m above the truth: a real, non-zero photometric gradient.
  TriangleMesh mesh = testing::PlaneMesh(testing::Plane{}, 20, 2.0, 0.4);
  TwoViews s = MakeTwoViews(mesh);
  std::vector<Eigen::Vector3d> gradient(mesh.vertices.size(), Eigen::Vector3d::Zero());
  Energy(s, mesh, &gradient);
  const auto normals = VertexNormals(mesh);
  int checked = 0, close = 0;
  double max_abs_gradient = 0;
  for (size_t v = 0; v < mesh.vertices.size(); v += 23) {
    const Eigen::Vector3f p = mesh.vertices[v];
    if (std::abs(p.x()) > 15 || std::abs(p.y()) > 15) continue;  // interior only
    const float eps = 2e-3f;
    TriangleMesh plus = mesh, minus = mesh;
    plus.vertices[v] += eps * normals[v];
    minus.vertices[v] -= eps * normals[v];
    const double fd = (Energy(s, plus, nullptr) - Energy(s, minus, nullptr)) / (2 * eps);
    const double analytic = gradient[v].dot(normals[v].cast<double>());
    max_abs_gradient = std::max(max_abs_gradient, std::abs(fd));
    ++checked;
    if (std::abs(analytic - fd) < 0.05 * std::abs(fd) + 0.02) ++close;
    else ADD_FAILURE() << "vertex " << v << ": analytic " << analytic << " fd " << fd;
  }
  EXPECT_GE(checked, 10);
  EXPECT_EQ(close, checked);
  EXPECT_GT(max_abs_gradient, 1.0);  // the check is not vacuous
}

}  // namespace
}  // namespace satmesh
