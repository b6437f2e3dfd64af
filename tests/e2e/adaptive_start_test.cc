// The adaptive start of a DSM start at full resolution (core/refine/level_start.cc,
// AdaptiveStart; issue 18's mesh whose resolution follows the surface) against the uniform
// 2-pixel remesh with its crease pass (flat_edge_px 0), on a 0.5 m tri-stereo city as the
// generator draws them (seed 5: not one of the seeds the default was measured on; a 150 m
// AOI to keep the test short). The adaptive mesh has fewer faces, larger ones where the
// surface is planar (roofs, streets, walls) and smaller ones at its creases, and is
// nearly as accurate. Measured: 97.5k faces against 178k; planar / crease faces' area-weighted
// median edge 1.72 / 1.20 m against 0.99 / 0.83 m; roofs NMAD 0.237 m against 0.262 m
// (session 46: 96.8k against 184k faces, roofs 0.173 against 0.200 m; session 47, the walls
// hung at once and level 0 run twice after the adaptive start too: 96.9k against 184k faces,
// 1.59 / 1.30 m against 0.98 / 0.89 m on the refined meshes, roofs 0.181 against 0.200 m).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <unistd.h>

#include "core/eval/scene_eval.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/topology.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/job.h"
#include "proto/job_spec_json.h"

namespace satmesh {
namespace {

// The area-weighted medians of the faces' mean edge length (the triangle size that covers
// half of that surface) over the planar faces (every neighbour's normal within
// kPlanarDeg) and over the crease faces (a neighbour's beyond kCreaseDeg): {planar, crease}.
constexpr double kPlanarDeg = 10, kCreaseDeg = 30;
std::pair<double, double> MedianEdges(const TriangleMesh& mesh) {
  const std::vector<Eigen::Vector3f> normals = FaceNormals(mesh);
  std::vector<float> max_angle(mesh.num_faces(), 0.f);
  std::unordered_map<uint64_t, int> first_face;
  for (int f = 0; f < int(mesh.num_faces()); ++f)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = uint32_t(mesh.faces[f][k]), b = uint32_t(mesh.faces[f][(k + 1) % 3]);
      if (a > b) std::swap(a, b);
      const auto [it, added] = first_face.try_emplace(uint64_t(a) << 32 | b, f);
      if (added) continue;
      const float cos = std::clamp(normals[f].dot(normals[it->second]), -1.f, 1.f);
      const float angle = float(std::acos(cos) * 180 / M_PI);
      max_angle[f] = std::max(max_angle[f], angle);
      max_angle[it->second] = std::max(max_angle[it->second], angle);
    }
  std::vector<std::pair<double, double>> planar, crease;  // (edge, area)
  for (size_t f = 0; f < mesh.num_faces(); ++f) {
    const Eigen::Vector3f a = mesh.vertices[mesh.faces[f][0]], b = mesh.vertices[mesh.faces[f][1]],
                          c = mesh.vertices[mesh.faces[f][2]];
    const double edge = ((b - a).norm() + (c - b).norm() + (a - c).norm()) / 3;
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (max_angle[f] < kPlanarDeg) planar.emplace_back(edge, area);
    if (max_angle[f] > kCreaseDeg) crease.emplace_back(edge, area);
  }
  const auto median = [](std::vector<std::pair<double, double>> v) {
    double total = 0, covered = 0;
    for (const auto& [edge, area] : v) total += area;
    std::sort(v.begin(), v.end());
    for (const auto& [edge, area] : v)
      if ((covered += area) >= total / 2) return edge;
    return 0.0;
  };
  return {median(planar), median(crease)};
}

TEST(AdaptiveStart, FewerFacesLargerWherePlanarAndAsAccurate) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("satmesh_adaptive_start_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const std::string scene = (dir / "scene").string();
  synth::SynthOptions options = synth::SynthPreset("default", /*seed=*/5);
  synth::SetAcquisition(&options, synth::Acquisition::kTriStereo);
  options.gsd_m = 0.5;
  options.city.aoi_size_m = 150;
  options.write_preview = false;
  synth::GenerateScene(scene, options);

  const JobSpec adaptive_spec = proto::ReadJobFile(scene + "/job.json");
  JobSpec uniform_spec = adaptive_spec;
  ASSERT_EQ(adaptive_spec.refine.flat_edge_px, -1);
  uniform_spec.refine.flat_edge_px = 0;
  const JobOutputs adaptive = RunJob(adaptive_spec, (dir / "adaptive").string());
  const JobOutputs uniform = RunJob(uniform_spec, (dir / "uniform").string());
  ASSERT_EQ(adaptive.tiles.size(), 1u);
  ASSERT_EQ(uniform.tiles.size(), 1u);
  ASSERT_TRUE(adaptive.tiles[0].ok) << adaptive.tiles[0].error;
  ASSERT_TRUE(uniform.tiles[0].ok) << uniform.tiles[0].error;
  const RefineResult& a = adaptive.tiles[0].refine;
  const RefineResult& u = uniform.tiles[0].refine;
  ASSERT_EQ(a.grid_start, 0);  // the remesh: a tri-stereo does not resolve the DSM's grid
  EXPECT_TRUE(a.adaptive_start);
  EXPECT_FALSE(u.adaptive_start);
  ASSERT_EQ(a.levels.size(), 2u);  // level 0 runs again, its creases fine already: as they are
  EXPECT_TRUE(a.levels[1].crease_pass);
  EXPECT_EQ(a.levels[1].num_faces, a.levels[0].num_faces);
  ASSERT_EQ(u.levels.size(), 2u);
  EXPECT_TRUE(u.levels[1].crease_pass);
  EXPECT_GT(u.levels[1].num_faces, u.levels[0].num_faces);

  const TriangleMesh am = ReadMesh(adaptive.mesh_path), um = ReadMesh(uniform.mesh_path);
  const auto [planar_a, crease_a] = MedianEdges(am);
  const auto [planar_u, crease_u] = MedianEdges(um);
  std::printf("faces: adaptive %zu, uniform %zu; median edge planar / crease faces: adaptive "
              "%.2f / %.2f m, uniform %.2f / %.2f m\n",
              am.num_faces(), um.num_faces(), planar_a, crease_a, planar_u, crease_u);
  EXPECT_LT(double(am.num_faces()), 0.8 * double(um.num_faces()));
  EXPECT_GT(planar_a, 1.3 * planar_u);  // larger triangles where the surface is planar
  // and smaller ones at its creases (measured on the refined mesh, whose walls hang plumb
  // since session 47: 0.82 of the planar ones' edge; 0.70 when they leaned)
  EXPECT_LT(crease_a, 0.9 * planar_a);

  const SceneEvaluation ea = EvaluateScene(scene, adaptive.mesh_path);
  const SceneEvaluation eu = EvaluateScene(scene, uniform.mesh_path);
  const auto& ra = ea.result.dsm.mask_raw;
  const auto& ru = eu.result.dsm.mask_raw;
  const auto& ma = ea.result.mesh3d;
  const auto& mu = eu.result.mesh3d;
  std::printf("roofs NMAD / perc-68, facades, F @0.5 m: adaptive %.3f / %.3f m, %.1f%%, %.1f; "
              "uniform %.3f / %.3f m, %.1f%%, %.1f; initial %.3f / %.3f m, %.1f%%, %.1f\n",
              ra.nmad_m, ra.perc68_m, 100 * ma.facade.completeness[1], 100 * ma.all.fscore[1],
              ru.nmad_m, ru.perc68_m, 100 * mu.facade.completeness[1], 100 * mu.all.fscore[1],
              ea.initial.dsm.mask_raw.nmad_m, ea.initial.dsm.mask_raw.perc68_m,
              100 * ea.initial.mesh3d.facade.completeness[1], 100 * ea.initial.mesh3d.all.fscore[1]);
  EXPECT_LE(ra.nmad_m, 1.05 * ru.nmad_m);
  EXPECT_LE(ra.perc68_m, 1.05 * ru.perc68_m);
  // Walls hung plumb (plumb_walls, session 46): the uniform mesh's finer walls, hung in its
  // crease pass as well, reached facades 54.7% and F 63.1 against the adaptive mesh's 53.9%
  // and 62.7 (hang off: 41.2 / 56.7 against 41.7 / 56.7). Since session 47 level 0 runs twice
  // after the adaptive start too (CreasePass): 62.0% / 67.1 against 62.1% / 67.0. A job with
  // several pairs is not bit-reproducible, so the bars are 2 points and 1 point.
  EXPECT_GE(ma.facade.completeness[1], mu.facade.completeness[1] - 0.02);
  EXPECT_GE(ma.all.fscore[1], mu.all.fscore[1] - 0.01);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace satmesh
