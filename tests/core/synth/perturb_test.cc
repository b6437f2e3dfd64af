#include "core/synth/perturb.h"

#include <gtest/gtest.h>

#include <cmath>

namespace satmesh::synth {
namespace {

// A flat n x n grid of 1 m cells (normals +z).
TriangleMesh Plane(int n) {
  TriangleMesh m;
  m.origin = {437000, 3355800, 10};
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.emplace_back(i, j, 0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      m.faces.emplace_back(a, a + 1, a + n + 2);
      m.faces.emplace_back(a, a + n + 2, a + n + 1);
    }
  return m;
}

TEST(PerturbOptions, DefaultsAreValid) { EXPECT_EQ(PerturbOptions{}.Check(), ""); }

TEST(PerturbOptions, InvalidWavelength) {
  PerturbOptions o;
  o.wavelength_m = 0;
  EXPECT_NE(o.Check().find("wavelength_m"), std::string::npos);
}

TEST(PerturbAlongNormals, SmoothNoiseOfTheAmplitudeAlongTheNormal) {
  const TriangleMesh plane = Plane(100);
  PerturbOptions o;
  o.amplitude_m = 1.0;
  const TriangleMesh moved = PerturbAlongNormals(plane, o);
  double sum2 = 0, max_step = 0;
  for (size_t i = 0; i < plane.vertices.size(); ++i) {
    EXPECT_EQ(moved.vertices[i].head<2>(), plane.vertices[i].head<2>());  // along +z only
    sum2 += double(moved.vertices[i].z()) * moved.vertices[i].z();
    if (i % 101 != 100) max_step = std::max(max_step, double(std::abs(moved.vertices[i + 1].z() - moved.vertices[i].z())));
  }
  // RMS of a sinusoid of amplitude 1 m: 0.71 m (a random sum of 8 waves: within 30%).
  EXPECT_NEAR(std::sqrt(sum2 / double(plane.vertices.size())), std::sqrt(0.5), 0.3);
  // Smooth: a 1 m step changes the height by at most 2 pi sqrt(8) / 15 m = 1.18 m
  // and far less in practice.
  EXPECT_LT(max_step, 0.8);
  EXPECT_EQ(PerturbAlongNormals(plane, o).vertices, moved.vertices);  // deterministic
  o.amplitude_m = 0;
  EXPECT_EQ(PerturbAlongNormals(plane, o).vertices, plane.vertices);
}

TEST(PerturbAlongNormals, SplitVerticesMoveTogether) {
  TriangleMesh m = Plane(2);
  m.vertices.push_back(m.vertices[4]);  // the centre vertex, split: face 0 uses the copy
  for (int k = 0; k < 3; ++k)
    if (m.faces[0][k] == 4) m.faces[0][k] = 9;
  const TriangleMesh moved = PerturbAlongNormals(m, {});
  EXPECT_EQ(moved.vertices[9], moved.vertices[4]);
}

}  // namespace
}  // namespace satmesh::synth
