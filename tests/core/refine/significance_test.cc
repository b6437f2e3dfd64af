#include "core/refine/significance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/common/error.h"
#include "core/mesh/topology.h"

#include "tests/core/mesh/mesh_fixtures.h"

namespace satmesh {
namespace {

// A 40 x 40 m grid of 1 m at z = 0 (the initial surface), refined: every vertex off by
// Gaussian noise of its sigma (0.1 m), and the vertices of the square [10, 20]^2 also by a
// real change of 1 m (10 sigmas); the vertex (5, 5) no image saw.
constexpr int kUnseen = 5 * 41 + 5;

struct Refined {
  TriangleMesh initial, refined;
  std::vector<float> noise;
};

Refined NoisyPlaneWithAChange() {
  Refined r;
  r.initial = testing::CreateGridMesh(40, 1.f);
  r.refined = r.initial;
  std::mt19937 gen(7);
  std::normal_distribution<float> n(0.f, 0.1f);
  r.refined.height_sigma.assign(r.refined.num_vertices(), 0.1f);
  for (size_t v = 0; v < r.refined.num_vertices(); ++v) {
    Eigen::Vector3f& p = r.refined.vertices[v];
    r.noise.push_back(n(gen));
    p.z() += r.noise.back();
    if (p.x() >= 10 && p.x() <= 20 && p.y() >= 10 && p.y() <= 20) p.z() += 1.f;
  }
  r.refined.height_sigma[kUnseen] = std::numeric_limits<float>::infinity();
  return r;
}

// The per-vertex test alone (keep_initial_scales 0).
SignificanceOptions PerVertex(double k, double reach_m, bool register_to_initial) {
  SignificanceOptions o;
  o.k = k;
  o.max_offset_m = reach_m;
  o.hold_boundary_xy = true;
  o.register_to_initial = register_to_initial;
  o.scales = 0;
  return o;
}

bool InChange(const Eigen::Vector3f& p) {
  return p.x() >= 11 && p.x() <= 19 && p.y() >= 11 && p.y() <= 19;  // away from its edge
}

TEST(KeepSignificantChanges, NoiseReturnsToTheInitialSurfaceARealChangeStays) {
  Refined r = NoisyPlaneWithAChange();
  TriangleMesh mesh = r.refined;
  const SignificanceStats stats =
      KeepSignificantChanges(r.initial, PerVertex(/*k=*/2, /*reach_m=*/3, /*register=*/true), &mesh);
  // Vertical rays along the grid's own border edges may miss it: nearly all others hit.
  EXPECT_GT(stats.vertices, mesh.num_vertices() - 4 * 40);
  double noise_before = 0, noise_after = 0;
  int flat = 0;
  for (size_t v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    if (InChange(p)) {
      // 10 sigmas: kept (weight 10^4 / (10^4 + 2^4) > 0.998), noise included.
      EXPECT_NEAR(p.z(), r.refined.vertices[v].z(), 0.01f) << v;
    } else if (p.x() < 8 || p.x() > 22 || p.y() < 8 || p.y() > 22) {
      noise_before += double(r.noise[v]) * r.noise[v];
      noise_after += double(p.z()) * p.z();
      ++flat;
      // Stays on the normal through the vertex (after the registration's shift): x, y
      // barely move on a plane.
      EXPECT_NEAR(p.x(), r.refined.vertices[v].x() - stats.registration_m.x(), 0.05f) << v;
    }
  }
  ASSERT_GT(flat, 1000);
  // Offsets within noise mostly undone: of 1 sigma RMS, under half a sigma is left (the
  // 5% of offsets beyond 2 sigmas stay, as a real change would).
  EXPECT_LT(std::sqrt(noise_after / flat), 0.5 * std::sqrt(noise_before / flat));
  // The vertex no image saw is back on the initial surface.
  EXPECT_NEAR(mesh.vertices[kUnseen].z(), 0.f, 1e-5f);
  EXPECT_GT(stats.mean_gain, 0.02);
  EXPECT_LT(stats.mean_gain, 0.3);
  // The registration sees no shift: vertically the noise's mean (0.1 m / sqrt(1681) ~ 2.4
  // mm), not pulled by the 1 m change; east-north only what the noise tilts the normals by
  // (~0.1 rad: a standard error of ~2.4 cm; 3 of them).
  EXPECT_NEAR(stats.registration_m.x(), 0, 0.075);
  EXPECT_NEAR(stats.registration_m.y(), 0, 0.075);
  EXPECT_NEAR(stats.registration_m.z(), 0, 0.01);
}

// A 40 x 40 m grid of 1 m with three 4 m high blocks (walls: normals with east-north
// parts), refined in a datum shifted by T from the initial's (as the images put it when
// the bias estimation's datum differs from the mesh's frame), with noise of its sigma
// (0.05 m) along z and a real change of 1 m on one block's roof.
TEST(KeepSignificantChanges, TheImagesDatumIsRegisteredToTheInitialSurface) {
  TriangleMesh initial = testing::CreateGridMesh(40, 1.f);
  const auto in_block = [](const Eigen::Vector3f& p) {
    return (p.x() >= 5 && p.x() <= 12 && p.y() >= 6 && p.y() <= 15) ||
           (p.x() >= 20 && p.x() <= 33 && p.y() >= 22 && p.y() <= 27) ||
           (p.x() >= 18 && p.x() <= 24 && p.y() >= 5 && p.y() <= 12);
  };
  const auto changed = [](const Eigen::Vector3f& p) {  // inside the third block's roof
    return p.x() >= 19 && p.x() <= 23 && p.y() >= 6 && p.y() <= 11;
  };
  for (auto& p : initial.vertices)
    if (in_block(p)) p.z() = 4.f;
  const Eigen::Vector3f shift(0.30f, -0.20f, 0.05f);
  TriangleMesh refined = initial;
  std::mt19937 gen(3);
  std::normal_distribution<float> noise(0.f, 0.05f);
  refined.height_sigma.assign(refined.num_vertices(), 0.05f);
  for (auto& p : refined.vertices) {
    if (changed(p)) p.z() += 1.f;
    p += shift + Eigen::Vector3f(0, 0, noise(gen));
  }
  TriangleMesh mesh = refined;
  const SignificanceStats stats = KeepSignificantChanges(initial, PerVertex(2, 3, true), &mesh);
  EXPECT_NEAR(stats.registration_m.x(), shift.x(), 0.02);
  EXPECT_NEAR(stats.registration_m.y(), shift.y(), 0.02);
  EXPECT_NEAR(stats.registration_m.z(), shift.z(), 0.01);
  // Back in the initial's frame: away from the border, the vertices are where the initial
  // surface has them (RMS 0.03 m: the noise, mostly undone); the change stays.
  double sum_sq = 0;
  int interior = 0;
  for (size_t v = 0; v < mesh.num_vertices(); ++v) {
    const Eigen::Vector3f& p0 = initial.vertices[v];
    if (p0.x() < 1 || p0.x() > 39 || p0.y() < 1 || p0.y() > 39) continue;
    ++interior;
    if (changed(p0)) {
      EXPECT_NEAR(mesh.vertices[v].z(), p0.z() + 1.f, 0.15f) << v;
      continue;
    }
    sum_sq += (mesh.vertices[v] - p0).squaredNorm();
  }
  ASSERT_GT(interior, 1400);
  EXPECT_LT(std::sqrt(sum_sq / interior), 0.04);
  // Without the registration the vertices keep the datum's 0.36 m east-north.
  TriangleMesh unregistered = refined;
  const SignificanceStats off = KeepSignificantChanges(initial, PerVertex(2, 3, false), &unregistered);
  EXPECT_EQ(off.registration_m, Eigen::Vector3d::Zero());
  double sum_sq_off = 0;
  for (size_t v = 0; v < unregistered.num_vertices(); ++v) {
    const Eigen::Vector3f& p0 = initial.vertices[v];
    if (p0.x() < 1 || p0.x() > 39 || p0.y() < 1 || p0.y() > 39 || changed(p0)) continue;
    sum_sq_off += (unregistered.vertices[v] - p0).squaredNorm();
  }
  EXPECT_GT(std::sqrt(sum_sq_off / interior), 0.3);

  // k = 0 (keep_initial_sigmas 0 on a mesh start): the registration alone, every offset
  // kept: the refined surface moved back by the translation, noise and change included.
  TriangleMesh only_registered = refined;
  const SignificanceStats only = KeepSignificantChanges(initial, PerVertex(0, 3, true), &only_registered);
  EXPECT_EQ(only.registration_m, stats.registration_m);
  EXPECT_DOUBLE_EQ(only.mean_gain, 1.0);
  const Eigen::Vector3f t = only.registration_m.cast<float>();
  for (size_t v = 0; v < only_registered.num_vertices(); ++v) {
    const Eigen::Vector3f& p0 = initial.vertices[v];
    if (p0.x() < 1 || p0.x() > 39 || p0.y() < 1 || p0.y() > 39) continue;  // border: z only
    EXPECT_LT((only_registered.vertices[v] - (refined.vertices[v] - t)).norm(), 1e-5f) << v;
  }
  TriangleMesh unchanged = refined;
  EXPECT_THROW(KeepSignificantChanges(initial, PerVertex(0, 3, false), &unchanged), Error);
}

TEST(RegisterToInitial, RecoversATranslationFromSlopesAndIgnoresOutliers) {
  // Normals in every direction, offsets n . T plus 5% gross outliers of 2 m.
  const Eigen::Vector3d t(0.4, -0.3, 0.1);
  std::mt19937 gen(11);
  std::normal_distribution<float> g(0.f, 1.f);
  std::vector<Eigen::Vector3f> normals;
  std::vector<double> offsets, sigmas;
  for (int i = 0; i < 2000; ++i) {
    Eigen::Vector3f n(g(gen), g(gen), g(gen));
    n.normalize();
    normals.push_back(n);
    offsets.push_back(n.cast<double>().dot(t) + 0.02 * g(gen) + (i % 20 == 0 ? 2.0 : 0.0));
    sigmas.push_back(i % 7 == 0 ? std::numeric_limits<double>::infinity() : 0.02);
  }
  const Eigen::Vector3d found = RegisterToInitial(normals, offsets, sigmas, 5.0);
  EXPECT_NEAR(found.x(), t.x(), 0.005);
  EXPECT_NEAR(found.y(), t.y(), 0.005);
  EXPECT_NEAR(found.z(), t.z(), 0.005);
  // Horizontal normals only: z unobserved, held at 0 by the prior.
  for (auto& n : normals) n = Eigen::Vector3f(n.x(), n.y(), 0).normalized();
  for (size_t i = 0; i < offsets.size(); ++i)
    offsets[i] = normals[i].cast<double>().dot(t);
  const Eigen::Vector3d flat_z = RegisterToInitial(normals, offsets, sigmas, 5.0);
  EXPECT_NEAR(flat_z.x(), t.x(), 1e-3);
  EXPECT_NEAR(flat_z.z(), 0.0, 1e-6);
  EXPECT_THROW(RegisterToInitial(normals, offsets, {}, 5.0), Error);
}

TEST(KeepSignificantChanges, OffsetsBeyondReachAndBadArgumentsAreLeftAlone) {
  Refined r = NoisyPlaneWithAChange();
  TriangleMesh mesh = r.refined;
  for (auto& p : mesh.vertices) p.z() += 5.f;  // 5 m off: beyond a reach of 3 m
  const TriangleMesh before = mesh;
  const SignificanceStats stats = KeepSignificantChanges(r.initial, PerVertex(2, 3, true), &mesh);
  EXPECT_EQ(stats.vertices, 0u);
  for (size_t v = 0; v < mesh.num_vertices(); ++v) EXPECT_EQ(mesh.vertices[v], before.vertices[v]);
  EXPECT_THROW(KeepSignificantChanges(r.initial, PerVertex(0, 3, false), &mesh), Error);  // nothing to do
  EXPECT_THROW(KeepSignificantChanges(r.initial, PerVertex(-1, 3, true), &mesh), Error);
  mesh.height_sigma.clear();
  EXPECT_THROW(KeepSignificantChanges(r.initial, PerVertex(2, 3, true), &mesh), Error);
}


// A start off by a smooth error (the initial surface at z = 0, the images' surface a
// plane wave of 0.6 m amplitude and 40 m wavelength: a roof or street off by 0.3-0.6 m
// over tens of metres, as a perturbed true mesh is), seen by the images with noise of
// 0.3 m per vertex, its sigma. Per vertex the error is within about 2 sigmas and mostly
// undone; pooled over the vertices around (radii 16, 8, 4 m at a GSD of 0.5 m) it is
// kept. Pure noise stays undone.
TEST(KeepSignificantChanges, PooledTestsKeepACoherentCorrectionThatEachVertexCannotShow) {
  const TriangleMesh initial = testing::CreateGridMesh(80, 1.f);
  const auto wave = [](const Eigen::Vector3f& p) {
    return 0.6f * std::sin(2.f * float(M_PI) * (0.8f * p.x() + 0.6f * p.y()) / 40.f);
  };
  for (const bool has_error : {true, false}) {
    TriangleMesh refined = initial;
    std::mt19937 gen(5);
    std::normal_distribution<float> noise(0.f, 0.3f);
    refined.height_sigma.assign(refined.num_vertices(), 0.3f);
    for (auto& p : refined.vertices) p.z() += (has_error ? wave(p) : 0.f) + noise(gen);
    // A vertex no image saw, on the wave's crest (40, 30), stayed where it started
    // (hold_unseen): its neighbours' coherent move says nothing about it.
    const auto unseen = std::find(initial.vertices.begin(), initial.vertices.end(),
                                  Eigen::Vector3f(40.f, 30.f, 0.f)) - initial.vertices.begin();
    ASSERT_LT(size_t(unseen), initial.num_vertices());
    ASSERT_NEAR(wave(initial.vertices[unseen]), 0.6f, 1e-4f);
    refined.vertices[unseen].z() = 0.f;
    refined.height_sigma[unseen] = std::numeric_limits<float>::infinity();
    SignificanceOptions pooled = PerVertex(2, 3, false);
    pooled.scales = 3;
    pooled.gsd_m = 0.5;
    pooled.floor_gsd = 0.15;
    TriangleMesh per_vertex_mesh = refined, pooled_mesh = refined;
    KeepSignificantChanges(initial, PerVertex(2, 3, false), &per_vertex_mesh);
    const SignificanceStats stats = KeepSignificantChanges(initial, pooled, &pooled_mesh);
    // RMS distance to the images' true surface (initial + wave, or the initial), away
    // from the border.
    const auto rms_error = [&](const TriangleMesh& m) {
      double sum = 0;
      int n = 0;
      for (size_t v = 0; v < m.num_vertices(); ++v) {
        const Eigen::Vector3f& p0 = initial.vertices[v];
        if (p0.x() < 8 || p0.x() > 72 || p0.y() < 8 || p0.y() > 72) continue;
        const float truth = has_error ? wave(p0) : 0.f;
        sum += double(m.vertices[v].z() - truth) * (m.vertices[v].z() - truth);
        ++n;
      }
      return std::sqrt(sum / n);
    };
    if (has_error) {
      const double start = rms_error(initial);  // the wave's RMS
      ASSERT_NEAR(start, 0.424, 0.01);
      // Per vertex: most of the wave returns to the initial surface (measured 0.324 m).
      EXPECT_GT(rms_error(per_vertex_mesh), 0.7 * start);
      // Pooled: the wave kept, what is left near the noise the per-vertex test keeps
      // anyway (0.127 m on noise alone; measured 0.172 m).
      EXPECT_LT(rms_error(pooled_mesh), 0.45 * start);
      EXPECT_GT(stats.pooled_share, 0.4);  // measured 0.53
      // Its neighbours' pooled offset (~0.6 m) not given to the vertex no image saw.
      EXPECT_NEAR(pooled_mesh.vertices[unseen].z(), 0.f, 1e-5f);
    } else {
      // Noise only: both undo most of it (of 0.3 m RMS, 0.127 m is left: the offsets
      // beyond 2 sigmas stay), the pooled tests adding less than 0.03 m to it.
      EXPECT_LT(rms_error(per_vertex_mesh), 0.135);
      EXPECT_LT(rms_error(pooled_mesh), rms_error(per_vertex_mesh) + 0.03);
      EXPECT_LT(stats.pooled_share, 0.1);
    }
  }
}

// A 4 m high block on a plane: the roof 0.5 m off (coherent, each vertex within its noise
// of 0.5 m), the ground not. Pooling stays on each vertex's own surface: the ground beside
// the block is not pulled up by the roof, which the steep sides separate from it.
TEST(PooledSignificantOffsets, StaysOnTheVertexsOwnSurface) {
  TriangleMesh mesh = testing::CreateGridMesh(60, 1.f);
  const auto on_roof = [](const Eigen::Vector3f& p) {
    return p.x() >= 20 && p.x() <= 40 && p.y() >= 20 && p.y() <= 40;
  };
  for (auto& p : mesh.vertices)
    if (on_roof(p)) p.z() = 4.f;
  const std::vector<Eigen::Vector3f> normals = VertexNormals(mesh);
  const VertexAdjacency adjacency = BuildVertexAdjacency(mesh);
  std::vector<double> offsets(mesh.num_vertices()), sigmas(mesh.num_vertices(), 0.5);
  for (size_t v = 0; v < offsets.size(); ++v) offsets[v] = on_roof(mesh.vertices[v]) ? 0.5 : 0.0;
  const std::vector<double> kept =
      PooledSignificantOffsets(mesh, adjacency, normals, offsets, sigmas, /*radius_m=*/8,
                               /*floor_m=*/0.05, /*k=*/2);
  int roof = 0, ground_near = 0;
  for (size_t v = 0; v < kept.size(); ++v) {
    const Eigen::Vector3f& p = mesh.vertices[v];
    if (on_roof(p) && p.x() >= 22 && p.x() <= 38 && p.y() >= 22 && p.y() <= 38) {
      // A full disc of ~200 vertices: sigma 0.069 m (0.047 from the vertices, the floor
      // 0.05), z 7.3, 99.9% kept; a quarter disc at the roof's corners: z 4.7, 97%.
      EXPECT_GT(kept[v], 0.45) << v;
      EXPECT_LE(kept[v], 0.5) << v;
      if (p.x() >= 28 && p.x() <= 32 && p.y() >= 28 && p.y() <= 32) EXPECT_NEAR(kept[v], 0.5, 0.005) << v;
      ++roof;
    } else if (!on_roof(p) && p.x() >= 14 && p.x() <= 46 && p.y() >= 14 && p.y() <= 46 &&
               normals[v].z() > 0.99f) {
      EXPECT_NEAR(kept[v], 0.0, 1e-9) << v;  // within 6 m of the roof, not pulled
      ++ground_near;
    }
  }
  EXPECT_GT(roof, 200);
  EXPECT_GT(ground_near, 300);
  EXPECT_THROW(PooledSignificantOffsets(mesh, adjacency, normals, offsets, {}, 8, 0.05, 2), Error);
  EXPECT_THROW(PooledSignificantOffsets(mesh, adjacency, normals, offsets, sigmas, 8, -0.1, 2),
               Error);
  EXPECT_THROW(PooledSignificantOffsets(mesh, VertexAdjacency{}, normals, offsets, sigmas, 8, 0.05, 2),
               Error);
}

}  // namespace
}  // namespace satmesh
