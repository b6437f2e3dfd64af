// End to end on a tiny synthetic scene (36 m, 3 views; generated once, ~3 s): tiled
// refinement, outputs, a failing tile, the tileset's bounding volumes.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <unistd.h>

#include "core/dsm/dsm.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_io.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/job.h"
#include "core/tiling/memory_budget.h"
#include "proto/job_spec_json.h"
#include "tests/scratch_dir.h"
#include "tests/tiny_scene.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

class TiledJob : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const synth::SynthOptions o = testing::TinySceneOptions();
    // Per process: ctest runs each test of this suite as its own process, in parallel.
    scene_ = (fs::temp_directory_path() / ("tiling_tiny_scene_" + std::to_string(::getpid()))).string();
    fs::remove_all(scene_);
    synth::GenerateScene(scene_, o);
  }
  static void TearDownTestSuite() { fs::remove_all(scene_); }

  // Cheap refinement: one coarse level, few iterations; 2 x 2 tiles of 18 m.
  static JobSpec Spec() {
    JobSpec spec = proto::ReadJobFile(scene_ + "/job.json");
    spec.refine.levels = 1;
    spec.refine.iterations_per_level = 3;
    spec.tiling.tile_size_m = 18;
    spec.tiling.overlap_m = 3;
    spec.tiling.workers = 2;
    return spec;
  }
  static std::string OutDir(const std::string& name) {
    const auto dir =
        fs::temp_directory_path() / ("tiling_job_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    testing::RemoveAtExit(dir);
    return dir.string();
  }
  static std::string scene_;
};
std::string TiledJob::scene_;

TEST_F(TiledJob, RefinesTilesAndAssemblesOutputs) {
  const std::string out = OutDir("grid");
  const JobOutputs o = RunJob(Spec(), out);
  ASSERT_EQ(o.tiles.size(), 4u);
  for (const auto& t : o.tiles) {
    EXPECT_TRUE(t.ok) << t.name << ": " << t.error;
    EXPECT_GT(t.core_faces, 100u);
    EXPECT_TRUE(fs::exists(fs::path(out) / ("tiles/" + t.name + ".glb")));
    EXPECT_FALSE(fs::exists(fs::path(out) / ("tiles/" + t.name + ".part.glb")));
  }
  EXPECT_EQ(o.assembly.tiles_ok, 4);
  const Dsm initial = ReadDsm(scene_ + "/initial/dsm.tif");
  const Dsm dsm = ReadDsm(o.dsm_path);
  EXPECT_EQ(dsm.width, initial.width);
  EXPECT_EQ(dsm.geo_transform, initial.geo_transform);
  // Holes away from the outer 2-cell band (where the boundary can pull in by a cell):
  // a gap along a seam would be a whole line of ~dsm.width cells.
  int interior_holes = 0;
  for (int row = 2; row < dsm.height - 2; ++row)
    for (int col = 2; col < dsm.width - 2; ++col)
      interior_holes += !std::isfinite(dsm.z[size_t(row) * dsm.width + col]);
  EXPECT_LT(interior_holes, dsm.width / 4) << "a gap along the seams?";
  // Mesh pieces were cut along the cores: the assembled mesh spans the AOI.
  const TriangleMesh mesh = ReadMesh(o.mesh_path);
  EXPECT_EQ(mesh.num_faces(), o.assembly.faces);
  // Seams: 4 shared edges, measured on both sides; the two refinements agree to a few cm.
  EXPECT_EQ(o.assembly.seams.size(), 4u);
  EXPECT_GT(o.assembly.seams_total.cells, 4 * 2 * 50);
  EXPECT_LT(o.assembly.seams_total.median_abs_m, 0.15);
  // The refinement's confidence: per vertex in mesh.ply, per cell in confidence.tif on
  // the DSM's grid, in [0, 1], high where the images pin the surface and not everywhere.
  ASSERT_EQ(mesh.height_sigma.size(), mesh.num_vertices());
  ASSERT_FALSE(o.assembly.confidence_path.empty());
  const Dsm confidence = ReadDsm(o.assembly.confidence_path);
  EXPECT_EQ(confidence.geo_transform, dsm.geo_transform);
  int cells = 0, high = 0, low = 0;
  for (float c : confidence.z) {
    if (std::isnan(c)) continue;
    ASSERT_GE(c, 0.f);
    ASSERT_LE(c, 1.f);
    ++cells, high += c > 0.5f, low += c < 0.2f;
  }
  EXPECT_GT(cells, dsm.width * dsm.height / 2);
  EXPECT_GT(high, cells / 10);
  EXPECT_GT(low, cells / 100);
}

TEST_F(TiledJob, TilesetBoundingVolumesContainTheirContent) {
  const std::string out = OutDir("tileset");
  JobSpec spec = Spec();
  spec.refine.iterations_per_level = 1;
  const JobOutputs o = RunJob(spec, out);
  proto::WriteJobJson(o, out);
  std::ifstream in(fs::path(out) / "tileset.json");
  const nlohmann::json ts = nlohmann::json::parse(in);
  EXPECT_EQ(ts["asset"]["version"], "1.1");
  EXPECT_GT(double(ts["geometricError"]), 0);
  const auto& root = ts["root"];
  EXPECT_EQ(root["refine"], "ADD");
  const auto root_region = root["boundingVolume"]["region"].get<std::vector<double>>();
  ASSERT_EQ(root["children"].size(), 4u);
  const CrsTransform geo_from_ecef("EPSG:4978", kWgs84Geographic3D);
  for (const auto& child : root["children"]) {
    const auto region = child["boundingVolume"]["region"].get<std::vector<double>>();
    ASSERT_EQ(region.size(), 6u);
    EXPECT_LT(region[0], region[2]);
    EXPECT_LT(region[1], region[3]);
    EXPECT_LE(region[4], region[5]);
    for (int k : {0, 1, 4}) EXPECT_GE(region[k], root_region[k]);
    for (int k : {2, 3, 5}) EXPECT_LE(region[k], root_region[k]);
    EXPECT_EQ(double(child["geometricError"]), 0.0);
    const auto m = child["transform"].get<std::vector<double>>();  // column-major
    ASSERT_EQ(m.size(), 16u);
    const TriangleMesh content = ReadMesh((fs::path(out) / child["content"]["uri"].get<std::string>()).string());
    ASSERT_GT(content.num_faces(), 0u);
    for (const auto& v : content.vertices) {
      const Eigen::Vector3d z_up(v.x(), -v.z(), v.y());  // glTF y-up -> tile z-up
      Eigen::Vector3d ecef;
      for (int r = 0; r < 3; ++r)
        ecef[r] = m[r] * z_up.x() + m[4 + r] * z_up.y() + m[8 + r] * z_up.z() + m[12 + r];
      const Eigen::Vector3d g = geo_from_ecef.Apply(ecef);
      const double lon = g.x() * M_PI / 180, lat = g.y() * M_PI / 180;
      ASSERT_TRUE(lon >= region[0] && lon <= region[2] && lat >= region[1] && lat <= region[3] &&
                  g.z() >= region[4] && g.z() <= region[5])
          << child["content"]["uri"] << " vertex " << g.transpose();
    }
  }
  std::ifstream metrics_in(fs::path(out) / "metrics.json");
  const nlohmann::json metrics = nlohmann::json::parse(metrics_in);
  EXPECT_EQ(metrics["tiles"].size(), 4u);
  EXPECT_EQ(metrics["totals"]["successful"], 4);
  EXPECT_GT(double(metrics["totals"]["peak_rss_mb"]), 0);
}

TEST_F(TiledJob, AFailingTileIsReportedAndTheOthersFinish) {
  // The east half of the initial DSM as nodata: tiles 1_0 and 1_1 have no surface.
  Dsm initial = ReadDsm(scene_ + "/initial/dsm.tif");
  for (int j = 0; j < initial.height; ++j)
    for (int i = initial.width / 2 - 10; i < initial.width; ++i) initial.at(i, j) = NAN;
  const std::string out = OutDir("failing");
  fs::create_directories(out);
  JobSpec spec = Spec();
  spec.initial_dsm = out + "/half.tif";
  WriteDsm(spec.initial_dsm, initial);
  spec.refine.iterations_per_level = 1;
  const JobOutputs o = RunJob(spec, out);
  EXPECT_EQ(o.assembly.tiles_ok, 2);
  EXPECT_EQ(o.assembly.tiles_failed, 2);
  for (const auto& t : o.tiles) {
    if (t.name[0] == '1') {
      EXPECT_FALSE(t.ok);
      EXPECT_NE(t.error.find("no valid cell"), std::string::npos) << t.error;
    } else {
      EXPECT_TRUE(t.ok) << t.error;
    }
  }
  const nlohmann::json metrics = proto::JobMetricsToJson(o);
  EXPECT_EQ(metrics["tiles"][1]["status"], "failed");
  EXPECT_EQ(metrics["tiles"][1]["error"]["code"], "invalid-input");
  EXPECT_EQ(o.assembly.tileset.tiles.size(), 2u);
  // Tile results survive JSON (a restarted server assembles from them).
  std::vector<TileResult> restored;
  for (const auto& t : metrics["tiles"]) restored.push_back(proto::TileResultFromJson(o.plan, t));
  const Assembly again = AssembleOutputs(o.plan, restored, out);
  EXPECT_EQ(again.faces, o.assembly.faces);
  EXPECT_EQ(again.tileset.region, o.assembly.tileset.region);
  EXPECT_EQ(again.tiles_failed, 2);
  for (size_t i = 0; i < restored.size(); ++i) {
    const TileResult& t = restored[i];
    if (!t.ok) {
      EXPECT_EQ(t.error_code, ErrorCode::kInvalidInput) << t.name;
    } else {  // the coarse start the tile took (grid_start -1: the grid or the remesh)
      EXPECT_EQ(t.refine.grid_start, o.tiles[i].refine.grid_start) << t.name;
      EXPECT_EQ(metrics["tiles"][i]["coarse_start"],
                t.refine.grid_start ? "grid" : t.refine.adaptive_start ? "adaptive" : "remesh");
    }
  }
  // The pipeline's assembly step from the restored results (what the server and the
  // queue's workers call): the same outputs.
  const JobOutputs assembled = AssembleJob(o.plan, restored, out);
  EXPECT_EQ(assembled.assembly.faces, o.assembly.faces);
  EXPECT_EQ(assembled.assembly.tiles_ok, 2);
  EXPECT_TRUE(o.assembly.seams.size() == 1u);  // 0_0 | 0_1 only
}

// A tiled job's levels summed over its tiles keep the crease pass apart from level 0 (it
// ran level 0 again on other faces): one entry each, the faces of each the tiles' sum.
TEST_F(TiledJob, TheJobsLevelsKeepTheCreasePassApart) {
  JobSpec spec = Spec();
  spec.refine.iterations_per_level = 1;
  spec.refine.crease_pass = 1;
  const JobOutputs o = RunJob(spec, OutDir("crease"));
  ASSERT_EQ(o.assembly.tiles_ok, 4);
  int level0_faces = 0, crease_faces = 0;
  for (const auto& t : o.tiles) {
    ASSERT_EQ(t.refine.levels.size(), 3u) << t.name;
    EXPECT_TRUE(t.refine.levels.back().crease_pass) << t.name;
    level0_faces += t.refine.levels[1].num_faces;
    crease_faces += t.refine.levels[2].num_faces;
  }
  const nlohmann::json levels = proto::JobMetricsToJson(o)["levels"];
  ASSERT_EQ(levels.size(), 3u);
  EXPECT_EQ(levels[1]["level"], 0);
  EXPECT_EQ(levels[1]["crease_pass"], false);
  EXPECT_EQ(levels[1]["faces"], level0_faces);
  EXPECT_EQ(levels[2]["level"], 0);
  EXPECT_EQ(levels[2]["crease_pass"], true);
  EXPECT_EQ(levels[2]["faces"], crease_faces);
  EXPECT_GT(crease_faces, level0_faces);
}

TEST_F(TiledJob, BiasesAreEstimatedOnceForTheJob) {
  JobSpec spec = Spec();
  spec.refine.estimate_bias = true;  // the scene has none: the estimates stay small
  spec.refine.iterations_per_level = 1;
  const JobOutputs o = RunJob(spec, OutDir("job_bias"));
  EXPECT_EQ(o.assembly.tiles_ok, 4);
  EXPECT_FALSE(o.bias_tile.empty());
  ASSERT_EQ(o.job_bias_px.size(), 3u);
  for (const auto& b : o.job_bias_px) EXPECT_LT(b.norm(), 0.2) << b.transpose();
  EXPECT_GT(o.bias_s, 0);
  for (const auto& t : o.tiles) {
    EXPECT_EQ(t.bias_s, 0) << t.name << ": estimated once for the job, not per tile";
    ASSERT_EQ(t.view_bias_px.size(), t.view_names.size()) << t.name;
    for (size_t v = 0; v < t.view_names.size(); ++v)
      for (size_t i = 0; i < spec.images.size(); ++i)
        if (spec.images[i].path == t.view_names[v]) {
          EXPECT_EQ(t.view_bias_px[v], o.job_bias_px[i]) << t.name << " view " << v;
        }
  }
}

TEST_F(TiledJob, BiasesDoNotDependOnTheTiling) {
  // The window is centred on the AOI: 2 x 2 tiles of 18 m and 3 x 3 of 12 m estimate the
  // same biases. (The window is at most 800 cells and at most a padded tile per side:
  // both tilings are given the same bound here, 70 cells, as every tiling of 800 cells or
  // more is. Before, the window was the middle of the tile nearest the AOI's centre.)
  JobSpec spec = Spec();
  spec.refine.estimate_bias = true;
  const JobPlan two = PlanJob(spec);  // tile 0_0 padded: 60 + 10 cells each way
  spec.tiling.tile_size_m = 12;
  spec.tiling.overlap_m = 4.5;  // the central tile padded: 40 + 2 x 15 = 70 cells
  const JobPlan three = PlanJob(spec);
  ASSERT_EQ(two.tiles.size(), 4u);
  ASSERT_EQ(three.tiles.size(), 9u);
  int index = -1;
  const std::vector<Eigen::Vector2d> a = EstimateJobBiases(spec, two, &index);
  const std::vector<Eigen::Vector2d> b = EstimateJobBiases(spec, three, &index);
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_LT((a[i] - b[i]).norm(), 1e-9) << i;
}

TEST_F(TiledJob, AOneTileJobLargerThanTheBiasWindowTakesItsBiasesFromTheWindow) {
  // One tile: within the window it estimates its own (nothing read twice); larger, the
  // job's biases come from the window at its centre, as for a tiled job.
  JobSpec spec = Spec();
  spec.refine.estimate_bias = true;
  spec.tiling.tile_size_m = 1000;
  const JobPlan plan = PlanJob(spec);
  ASSERT_EQ(plan.tiles.size(), 1u);
  const PixelWindow& padded = plan.tiles[0].padded_cells;
  const int side = std::max(padded.width, padded.height);
  EXPECT_TRUE(EstimateJobBiasesOnce(spec, plan, {}, side).bias_px.empty());
  const JobBiases window = EstimateJobBiasesOnce(spec, plan, {}, side / 2);
  ASSERT_EQ(window.bias_px.size(), spec.images.size());
  EXPECT_EQ(window.tile, plan.tiles[0].Name());
  EXPECT_GT(window.seconds, 0);
  // The scene has no bias: the estimates from half the tile's side stay small.
  for (const auto& b : window.bias_px) EXPECT_LT(b.norm(), 0.2) << b.transpose();
}

TEST_F(TiledJob, WhenTheBiasWindowHasNoSurfaceEachTileEstimatesItsOwn) {
  // The initial DSM's cells in the job's bias window (centred on the AOI, a padded tile's
  // size) and west of it as nodata: the job's biases cannot be estimated there.
  JobSpec spec = Spec();
  const JobPlan plan = PlanJob(spec);
  const PixelWindow& a = plan.aoi_cells;
  const int w = plan.tiles[0].padded_cells.width, h = plan.tiles[0].padded_cells.height;
  const int col1 = a.col0 + (a.width - w) / 2 + w, row0 = a.row0 + (a.height - h) / 2;
  Dsm initial = ReadDsm(scene_ + "/initial/dsm.tif");
  for (int j = row0; j < row0 + h; ++j)
    for (int i = 0; i < col1; ++i) initial.at(i, j) = NAN;
  const std::string out = OutDir("bias_fallback");
  fs::create_directories(out);
  spec.initial_dsm = out + "/holed.tif";
  WriteDsm(spec.initial_dsm, initial);
  spec.refine.estimate_bias = true;
  spec.refine.iterations_per_level = 1;
  const JobOutputs o = RunJob(spec, out);
  EXPECT_TRUE(o.job_bias_px.empty());
  EXPECT_GE(o.assembly.tiles_ok, 1);
  for (const auto& t : o.tiles)
    if (t.ok) {
      EXPECT_EQ(t.view_bias_px.size(), t.view_names.size()) << t.name << ": its own";
    }
}

TEST_F(TiledJob, ATinyBudgetIsRefusedNamingBudgetAndNeed) {
  JobSpec spec = Spec();
  spec.tiling = TilingOptions{};
  spec.tiling.memory_budget_mb = 1;
  try {
    RunJob(spec, OutDir("tiny_budget"));
    FAIL() << "a 1 MB budget was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    const std::string message = e.what();
    EXPECT_NE(message.find("needs an estimated"), std::string::npos) << message;
    EXPECT_NE(message.find("memory budget is 1 MB"), std::string::npos) << message;
    EXPECT_NE(message.find("3 views"), std::string::npos) << message;
  }
}

TEST_F(TiledJob, AJobOverTheBudgetIsTiledToFitIt) {
  JobSpec spec = Spec();
  spec.tiling = TilingOptions{};
  spec.tiling.overlap_m = 3;
  const JobPlan whole = PlanJob(spec);
  ASSERT_EQ(whole.tiles.size(), 1u);
  EXPECT_EQ(whole.tiles[0].memory.views, 3);
  EXPECT_GT(whole.tiles[0].memory.window_px, 100.0 * 100.0);
  // A budget of half the one piece's need over the fixed part.
  spec.tiling.memory_budget_mb = kBaseMb + 0.5 * (whole.tiles[0].memory.peak_mb - kBaseMb);
  const JobPlan tiled = PlanJob(spec);
  EXPECT_TRUE(tiled.auto_tiled);
  EXPECT_GT(tiled.tiles.size(), 1u);
  for (const PlannedTile& t : tiled.tiles) EXPECT_LE(t.memory.peak_mb, spec.tiling.memory_budget_mb);
}

TEST_F(TiledJob, AGivenTileOverTheBudgetFailsNamingIt) {
  JobSpec spec = Spec();
  spec.tiling.memory_budget_mb = 1;
  const JobPlan plan = PlanJob(spec);  // the tiling is the job's: not changed
  ASSERT_EQ(plan.tiles.size(), 4u);
  const TileResult r = RunTile(spec, plan, 0, OutDir("given_over_budget"));
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("tile 0_0 needs an estimated"), std::string::npos) << r.error;
  EXPECT_GT(r.estimated_peak_mb, 1);
}

TEST_F(TiledJob, OneTileJobMatchesTheWholeDsm) {
  JobSpec spec = Spec();
  spec.tiling = TilingOptions{};
  spec.refine.levels = 0;
  spec.refine.iterations_per_level = 1;
  const std::string out = OutDir("single");
  const JobOutputs o = RunJob(spec, out);
  ASSERT_EQ(o.tiles.size(), 1u);
  EXPECT_GT(o.refine.mesh.num_faces(), 0u);  // single-tile jobs keep the mesh (bench)
  EXPECT_EQ(o.view_names.size(), 3u);
  EXPECT_TRUE(o.assembly.seams.empty());
  // The job's files are the tile's (copied: AssembleOutputs' one-tile path), with its counts.
  const auto bytes = [](const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(bytes(o.assembly.mesh_path), bytes(fs::path(out) / TilePiecePath(o.plan.tiles[0])));
  const TriangleMesh mesh = ReadMesh(o.assembly.mesh_path);
  EXPECT_EQ(mesh.num_faces(), o.tiles[0].core_faces);
  EXPECT_EQ(o.assembly.faces, o.tiles[0].core_faces);
  EXPECT_EQ(o.assembly.vertices, mesh.num_vertices());
  EXPECT_EQ(mesh.height_sigma.size(), mesh.num_vertices());
  const Dsm dsm = ReadDsm(o.assembly.dsm_path);
  EXPECT_EQ(dsm.width, o.plan.aoi_cells.width);
  EXPECT_EQ(dsm.height, o.plan.aoi_cells.height);
  ASSERT_FALSE(o.assembly.confidence_path.empty());
  EXPECT_EQ(ReadDsm(o.assembly.confidence_path).width, dsm.width);
  // Running the tile again is harmless (same files, atomically replaced).
  const TileResult again = RunTile(spec, o.plan, 0, out);
  EXPECT_TRUE(again.ok) << again.error;
  EXPECT_EQ(again.core_faces, o.tiles[0].core_faces);
}

}  // namespace
}  // namespace satmesh
