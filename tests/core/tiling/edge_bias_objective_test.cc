// Why the refinement takes half a pixel off its walls (core/refine/edge_bias.h): its own
// objective, on a synthetic city rendered from a known mesh, scores that mesh best with
// its walls moved out. Mixed pixels at a roof edge move with the roof between views, so
// the foreground claiming them makes the windows agree. If the objective ever stops
// preferring fattened walls, the correction DeflateOccludingEdges applies is wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "core/dsm/dsm.h"
#include "core/mesh/mesh_io.h"
#include "core/refine/edge_bias.h"
#include "core/refine/surface_comparison.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/tile_input.h"
#include "proto/job_spec_json.h"
#include "tests/scratch_dir.h"
#include "tests/tiny_scene.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

TEST(PhotometricObjective, ScoresTheTrueWallsBelowWallsHalfAPixelOut) {
  const synth::SynthOptions o = testing::TinySceneOptions();
  const fs::path scene = fs::temp_directory_path() / ("edge_bias_scene_" + std::to_string(::getpid()));
  fs::remove_all(scene);
  testing::RemoveAtExit(scene);
  synth::GenerateScene(scene.string(), o);
  const JobSpec spec = proto::ReadJobFile((scene / "job.json").string());
  Dsm dsm = ReadDsm(spec.initial_dsm);
  const double cell = std::abs(dsm.geo_transform[1]);
  const TileInput input = PrepareTileInput(spec, std::move(dsm), CoarseCellSize(spec.refine, cell));
  const TriangleMesh file = ReadMesh((scene / "truth" / "mesh.ply").string());
  const TriangleMesh truth = MeshInFrame(file, file.crs, input.refine.frame);
  const double half_px = 0.5 * o.gsd_m;
  TriangleMesh out = truth, in = truth;
  ASSERT_GT(DeflateOccludingEdges(-half_px, &out).moved, 1000u);
  DeflateOccludingEdges(half_px, &in);
  const std::vector<std::pair<int, int>> pairs = {{0, 1}, {0, 2}, {1, 2}};
  const auto zncc = CommonWindowZncc(input.refine, {truth, out, in}, pairs, 0, spec.refine);
  auto mean = [&](size_t s) {
    double sum = 0;
    long n = 0;
    for (const auto& c : zncc[s]) sum += c.mean_zncc * double(c.windows), n += c.windows;
    return sum / double(n);
  };
  std::printf("mean ZNCC over the common windows: walls half a pixel out %.4f, the truth %.4f, "
              "half a pixel in %.4f\n", mean(1), mean(0), mean(2));
  EXPECT_GT(mean(1), mean(0));
  EXPECT_GT(mean(0), mean(2));
}

}  // namespace
}  // namespace satmesh
