#include "core/refine/photometric_gradient.h"

#include <gtest/gtest.h>

#include "core/image/image.h"
#include "core/mesh/topology.h"
#include "core/refine/warp.h"
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

// E = M_01 + M_10 = -Σ ZNCC, and optionally its gradient; *valid_pixels counts the
// pixels used. The hit maps carry ray cosines, as in the refinement (the warp's AVX2
// path needs them).
double Energy(TwoViews& s, const TriangleMesh& mesh, std::vector<Eigen::Vector3d>* gradient,
              long* valid_pixels = nullptr) {
  RayScene scene(mesh);
  const auto normals = FaceNormals(mesh);
  for (auto& v : s.views) CastHitMap(scene, &v, &normals);
  double e = 0;
  for (int d = 0; d < 2; ++d) {
    const PairEnergy pair = AccumulatePhotometricGradient(s.views[d], s.views[1 - d], mesh, normals,
                                                          s.options, gradient, nullptr);
    e -= pair.sum_zncc;
    if (valid_pixels) *valid_pixels += pair.num_valid_pixels;
  }
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

// Two triangles sharing an edge (vertices 1, 2): over 70 pair-directions (more than the
// 32 the face bits hold between counts), count the directions that saw each vertex.
TEST(GradientAccumulator, CountsTheDirectionsThatSawEachVertex) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  mesh.faces = {{0, 1, 2}, {1, 3, 2}};
  const VertexAdjacency adjacency = BuildVertexAdjacency(mesh);
  GradientAccumulator accumulator;
  accumulator.Reset(mesh, adjacency);
  int expected_face0 = 0, expected_face1 = 0, expected_both = 0;
  for (int d = 0; d < 70; ++d) {
    accumulator.BeginDirection();
    const bool face0 = d % 3 == 0, face1 = d % 5 == 0;
    for (int pixel = 0; pixel < 4; ++pixel) {  // several pixels a face: counted once
      if (face0) accumulator.AddPixel(0, 0.25f, 0.25f, 1.f);
      if (face1) accumulator.AddPixel(1, 0.5f, 0.25f, 2.f);
    }
    expected_face0 += face0, expected_face1 += face1, expected_both += face0 || face1;
  }
  const std::vector<Eigen::Vector3f> normals(2, Eigen::Vector3f::UnitZ());
  std::vector<Eigen::Vector3d> gradient(4, Eigen::Vector3d::Zero());
  std::vector<int> seen(4, 0);
  accumulator.AddTo(normals, &gradient, &seen);
  EXPECT_EQ(seen[0], expected_face0);  // 24
  EXPECT_EQ(seen[3], expected_face1);  // 14
  EXPECT_EQ(seen[1], expected_both);   // 38
  EXPECT_EQ(seen[2], expected_both);
  // Vertex 0: face 0's weight 1 - u - v = 0.5, g = 1, 4 pixels a direction, 24 directions.
  EXPECT_NEAR(gradient[0].z(), 0.5 * 4 * expected_face0, 1e-4);
  // Vertex 3 (face 1's second vertex, weight u = 0.5, g = 2).
  EXPECT_NEAR(gradient[3].z(), 0.5 * 2 * 4 * expected_face1, 1e-4);
  EXPECT_EQ(gradient[0].x(), 0.0);
}

// AddTo gathers each vertex's faces: a degenerate face that names a vertex at two corners
// gives it both corners' weights, as a scatter over the faces' corners would.
TEST(GradientAccumulator, GathersBothCornersOfADegenerateFace) {
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.faces = {{0, 1, 2}, {0, 0, 1}};
  const VertexAdjacency adjacency = BuildVertexAdjacency(mesh);
  GradientAccumulator accumulator;
  accumulator.Reset(mesh, adjacency);
  accumulator.BeginDirection();
  accumulator.AddPixel(0, 0.25f, 0.25f, 1.f);  // weights 0.5, 0.25, 0.25
  accumulator.AddPixel(1, 0.5f, 0.25f, 2.f);   // weights 0.5, 1.0, 0.5
  const std::vector<Eigen::Vector3f> normals(2, Eigen::Vector3f::UnitZ());
  std::vector<Eigen::Vector3d> gradient(3, Eigen::Vector3d::Zero());
  std::vector<int> seen(3, 0);
  accumulator.AddTo(normals, &gradient, &seen);
  EXPECT_NEAR(gradient[0].z(), 0.5 + 0.5 + 1.0, 1e-6);  // face 0's corner 0, face 1's 0 and 1
  EXPECT_NEAR(gradient[1].z(), 0.25 + 0.5, 1e-6);
  EXPECT_NEAR(gradient[2].z(), 0.25, 1e-6);
  EXPECT_EQ(seen, (std::vector<int>{1, 1, 1}));
}

TEST(AccumulatePhotometricGradient, VectorizedWarpMatchesTheScalarReference) {
  if (!WarpHasAvx2()) GTEST_SKIP() << "no AVX2 on this CPU: the scalar warp is the only one";
  TriangleMesh mesh = testing::PlaneMesh(testing::Plane{}, 20, 2.0, 0.4);
  TwoViews s = MakeTwoViews(mesh);
  std::vector<Eigen::Vector3d> scalar(mesh.vertices.size(), Eigen::Vector3d::Zero());
  std::vector<Eigen::Vector3d> vectorized = scalar;
  long scalar_pixels = 0, vectorized_pixels = 0;
  s.options.vectorized = false;
  const double e_scalar = Energy(s, mesh, &scalar, &scalar_pixels);
  s.options.vectorized = true;
  const double e_vectorized = Energy(s, mesh, &vectorized, &vectorized_pixels);
  // Float lattice vs double: a pixel on a boundary may flip, nothing more.
  EXPECT_GT(scalar_pixels, 10000);
  EXPECT_NEAR(double(vectorized_pixels), double(scalar_pixels), 1e-3 * scalar_pixels);
  EXPECT_NEAR(e_vectorized, e_scalar, 1e-6 * std::abs(e_scalar));  // measured 3.5e-8
  double max_norm = 0, max_diff = 0;
  for (size_t v = 0; v < scalar.size(); ++v) {
    max_norm = std::max(max_norm, scalar[v].norm());
    max_diff = std::max(max_diff, (vectorized[v] - scalar[v]).norm());
  }
  EXPECT_GT(max_norm, 1.0);
  EXPECT_LT(max_diff, 2e-4 * max_norm);  // measured 1.9e-5
}

}  // namespace
}  // namespace satmesh
