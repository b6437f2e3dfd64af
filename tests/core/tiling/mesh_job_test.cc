// Jobs and their meshes on a tiny synthetic scene (36 m, tri-stereo; generated once):
// outputs without debris on a many-tile job, jobs that start from a mesh (the scene's
// truth mesh), chaining a result, and bad meshes refused naming file and problem.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "core/dsm/dsm.h"
#include "core/geo/crs.h"
#include "core/mesh/mesh_clean.h"
#include "core/mesh/mesh_io.h"
#include "core/refine/bias_estimation.h"
#include "core/synth/scene_writer.h"
#include "core/tiling/initial_mesh.h"
#include "core/tiling/job.h"
#include "core/tiling/tile_input.h"
#include "proto/job_spec_json.h"
#include "tests/scratch_dir.h"
#include "tests/tiny_scene.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

class MeshJob : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const synth::SynthOptions o = testing::TinySceneOptions();
    scene_ = (fs::temp_directory_path() / ("mesh_job_scene_" + std::to_string(::getpid()))).string();
    fs::remove_all(scene_);
    synth::GenerateScene(scene_, o);
  }
  static void TearDownTestSuite() { fs::remove_all(scene_); }

  // Cheap refinement: one coarse level, few iterations.
  static JobSpec Spec() {
    JobSpec spec = proto::ReadJobFile(scene_ + "/job.json");
    spec.refine.levels = 1;
    spec.refine.iterations_per_level = 3;
    spec.tiling.overlap_m = 3;
    spec.tiling.workers = 2;
    return spec;
  }
  static std::string OutDir(const std::string& name) {
    const auto dir = fs::temp_directory_path() / ("mesh_job_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(dir);
    testing::RemoveAtExit(dir);
    return dir.string();
  }
  // Every mesh a job wrote: mesh.ply and each tile's .ply and .glb. (A .glb may repeat a
  // vertex's position: Draco's edgebreaker splits a non-manifold vertex in two.)
  static void ExpectNoDebris(const std::string& out) {
    EXPECT_EQ(FindDebris(ReadMesh(out + "/mesh.ply")).ToString(), MeshDebris{}.ToString())
        << "mesh.ply";
    for (const auto& entry : fs::directory_iterator(fs::path(out) / "tiles")) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".ply" && ext != ".glb") continue;
      MeshDebris debris = FindDebris(ReadMesh(entry.path().string()));
      if (ext == ".glb") debris.close_vertices = 0;
      EXPECT_EQ(debris.ToString(), MeshDebris{}.ToString()) << entry.path();
    }
  }
  // The scene's area (the initial DSM's extent), where the images look.
  static std::vector<Eigen::Vector2d> SceneAoi() {
    const Dsm dsm = ReadDsm(scene_ + "/initial/dsm.tif");
    const double x0 = dsm.geo_transform[0], y1 = dsm.geo_transform[3];
    const double x1 = x0 + dsm.width * dsm.geo_transform[1], y0 = y1 + dsm.height * dsm.geo_transform[5];
    return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  }
  static std::string scene_;
};
std::string MeshJob::scene_;

TEST_F(MeshJob, ManyTilesFromTheDsmLeaveNoDebris) {
  JobSpec spec = Spec();
  spec.tiling.tile_size_m = 9;  // 4 x 4 tiles
  const std::string out = OutDir("debris_dsm");
  const JobOutputs o = RunJob(spec, out);
  ASSERT_EQ(o.tiles.size(), 16u);
  EXPECT_EQ(o.assembly.tiles_ok, 16);
  ExpectNoDebris(out);
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

// The median |refined - truth| over the truth DSM's cells where both have a surface.
double MedianAbsDsmError(const std::string& result_dsm, const std::string& truth_dsm) {
  const Dsm result = ReadDsm(result_dsm), truth = ReadDsm(truth_dsm);
  std::vector<double> diffs;
  for (int j = 0; j < truth.height; ++j)
    for (int i = 0; i < truth.width; ++i) {
      const double x = truth.geo_transform[0] + (i + 0.5) * truth.geo_transform[1];
      const double y = truth.geo_transform[3] + (j + 0.5) * truth.geo_transform[5];
      const int ri = int(std::floor((x - result.geo_transform[0]) / result.geo_transform[1]));
      const int rj = int(std::floor((y - result.geo_transform[3]) / result.geo_transform[5]));
      if (ri < 0 || rj < 0 || ri >= result.width || rj >= result.height) continue;
      const float a = result.at(ri, rj), b = truth.at(i, j);
      if (std::isfinite(a) && std::isfinite(b)) diffs.push_back(std::abs(double(a) - b));
    }
  if (diffs.empty()) return INFINITY;
  std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
  return diffs[diffs.size() / 2];
}

TEST_F(MeshJob, ThePlanPreparesTheMeshOnceAndTilesClipTheSame) {
  // PlanJob repairs the mesh, fills its holes and puts it in the plan's CRS once; a tile
  // clips that. A plan without it (made elsewhere) gives the tile the same input.
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.initial_mesh.path = scene_ + "/truth/mesh.ply";
  spec.aoi.polygon = SceneAoi();
  spec.tiling.tile_size_m = 18;
  const JobPlan plan = PlanJob(spec);
  ASSERT_TRUE(plan.initial_mesh);
  EXPECT_EQ(plan.initial_mesh->crs, plan.dsm.crs_wkt);
  ASSERT_GE(plan.tiles.size(), 2u);
  JobPlan bare = plan;
  bare.initial_mesh.reset();
  for (int i : {0, int(plan.tiles.size()) - 1}) {
    const TileInput a = PrepareTileInput(spec, plan, i), b = PrepareTileInput(spec, bare, i);
    ASSERT_GT(a.refine.initial_mesh.num_faces(), 100u);
    EXPECT_EQ(a.refine.initial_mesh.faces, b.refine.initial_mesh.faces) << i;
    EXPECT_EQ(a.refine.initial_mesh.vertices, b.refine.initial_mesh.vertices) << i;
  }
}

// The ground shift t (east, north, metres) by which a bias estimate's block sits off the
// truth: est_v = -b_v + J_v t for injected biases b_v (least squares over the views; J_v
// by central differences at the frame's origin).
Eigen::Vector2d DatumOffTheTruth(const RefineInput& input, const BiasEstimate& e,
                                 const std::vector<Eigen::Vector2d>& b) {
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (size_t v = 0; v < input.views.size(); ++v) {
    Eigen::Matrix2d j;
    for (int axis = 0; axis < 2; ++axis) {
      Eigen::Vector3d d = Eigen::Vector3d::Zero();
      d[axis] = 0.5;
      const RpcModel& rpc = input.views[v].rpc;
      j.col(axis) = rpc.PixelFromGeo(input.frame.GeoFromLocal(d)) - rpc.PixelFromGeo(input.frame.GeoFromLocal(-d));
    }
    normal += j.transpose() * j;
    rhs += j.transpose() * (e.bias_col_row_px[v] + b[v]);
  }
  return normal.inverse() * rhs;
}

TEST_F(MeshJob, TheImageBlockIsPutOnTheInitialMesh) {
  // Each image's RPC biased (~1 px, as vendors' are): the pairs see only the differences,
  // not where the block sits. From the truth mesh (register_to_initial: on for a mesh
  // start) the block is put where its pairs agree on the mesh, the truth's datum; the
  // datum of minimum corrections (off) sits where the biases' mean puts it.
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.initial_mesh.path = scene_ + "/truth/mesh.ply";
  spec.aoi.polygon = SceneAoi();
  // Their mean is ~1.4 px: minimum corrections put the block ~0.4 m off.
  const std::vector<Eigen::Vector2d> b = {{1.4, -0.9}, {0.8, -1.5}, {1.6, -0.4}};
  ASSERT_EQ(spec.images.size(), b.size());
  for (size_t i = 0; i < b.size(); ++i) spec.images[i].bias_col_row_px = b[i];
  const TileInput tile = PrepareTileInput(spec, PlanJob(spec), 0);
  ASSERT_TRUE(tile.refine.initial_is_mesh);
  for (size_t i = 0; i < b.size(); ++i) ASSERT_EQ(tile.view_names[i], spec.images[i].path);
  BiasOptions options;
  options.refine = spec.refine;
  const BiasEstimate on = EstimateRefineBiases(tile.refine, options);
  options.refine.register_to_initial = 0;
  const BiasEstimate off = EstimateRefineBiases(tile.refine, options);
  const Eigen::Vector2d t_on = DatumOffTheTruth(tile.refine, on, b);
  const Eigen::Vector2d t_off = DatumOffTheTruth(tile.refine, off, b);
  EXPECT_GT(t_off.norm(), 0.15) << t_off.transpose();
  EXPECT_LT(t_on.norm(), 0.06) << t_on.transpose();
}

TEST_F(MeshJob, WithoutAnAoiTheTilesCoverWhatTheImagesSee) {
  // The truth mesh has 45 m of ground around the 36 m the images see: planned on the
  // mesh's whole extent, the outer tiles would have no image.
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.initial_mesh.path = scene_ + "/truth/mesh.ply";
  spec.tiling.tile_size_m = 18;
  spec.refine.iterations_per_level = 1;
  const JobOutputs o = RunJob(spec, OutDir("no_aoi"));
  // The images (182 px of 0.3 m) see ~66 m of the mesh's 126 m.
  EXPECT_LT(o.plan.aoi_cells.width * o.plan.dsm.geo_transform[1], 70);
  EXPECT_LT(o.plan.aoi_cells.height * o.plan.dsm.geo_transform[1], 70);
  for (const auto& t : o.tiles) EXPECT_TRUE(t.ok) << t.name << ": " << t.error;
}

TEST_F(MeshJob, StartsFromTheTruthMeshAndKeepsIt) {
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.initial_mesh.path = scene_ + "/truth/mesh.ply";
  spec.tiling.tile_size_m = 18;  // 2 x 2 over the images' area (the mesh has 45 m more ground)
  spec.aoi.polygon = SceneAoi();
  const std::string out = OutDir("truth_start");
  const JobOutputs o = RunJob(spec, out);
  EXPECT_EQ(o.assembly.tiles_failed, 0);
  ASSERT_GE(o.tiles.size(), 4u);
  for (const auto& t : o.tiles) EXPECT_TRUE(t.ok) << t.name << ": " << t.error;
  // The grid: the images' GSD (the scene's 0.3 m) over the mesh.
  EXPECT_NEAR(o.plan.dsm.geo_transform[1], 0.3, 0.03);
  ExpectNoDebris(out);
  const double kept = MedianAbsDsmError(o.dsm_path, scene_ + "/truth/dsm.tif");
  EXPECT_LT(kept, 0.1);
  // Without the last step (keep_initial_sigmas, 2 for a mesh start) the surface follows
  // the matching noise further away from the truth.
  spec.refine.keep_initial_sigmas = 0;
  const JobOutputs free = RunJob(spec, OutDir("truth_start_free"));
  const double drifted = MedianAbsDsmError(free.dsm_path, scene_ + "/truth/dsm.tif");
  EXPECT_LT(kept, 0.7 * drifted) << "kept " << kept << " m, without the step " << drifted << " m";
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// What PlanJob (the CLI's and the server's first step) says about a spec.
std::string PlanError(const JobSpec& spec) {
  try {
    PlanJob(spec);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST_F(MeshJob, BadMeshesAreRefusedNamingFileAndProblem) {
  const std::string dir = OutDir("bad_meshes");
  fs::create_directories(dir);
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.aoi.polygon = SceneAoi();
  const auto with_mesh = [&](const std::string& path) {
    JobSpec s = spec;
    s.initial_mesh.path = path;
    return s;
  };
  const std::string ply_head = "ply\nformat ascii 1.0\ncomment crs EPSG:32617\n";
  WriteText(dir + "/garbage.ply", "this is not a mesh\n");
  WriteText(dir + "/nan.ply", ply_head + "element vertex 3\nproperty double x\nproperty double y\n"
                              "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
                              "end_header\n0 0 0\nnan 1 0\n1 0 0\n3 0 1 2\n");
  WriteText(dir + "/no_faces.ply", ply_head + "element vertex 1\nproperty double x\nproperty double y\n"
                                   "property double z\nend_header\n0 0 0\n");
  TriangleMesh truth = ReadMesh(scene_ + "/truth/mesh.ply");
  for (auto& f : truth.faces) std::swap(f[1], f[2]);
  WriteMesh(dir + "/inverted.ply", truth);
  for (auto& f : truth.faces) std::swap(f[1], f[2]);
  truth.crs.clear();
  WriteMesh(dir + "/no_crs.obj", truth);
  JobSpec no_crs = with_mesh(dir + "/no_crs.obj");
  no_crs.output_crs.clear();

  const std::vector<std::pair<JobSpec, std::string>> cases = {
      {with_mesh(dir + "/missing.ply"), "initial.mesh: '" + dir + "/missing.ply' does not exist"},
      {with_mesh(dir), "no " + dir + "/mesh.ply (a previous job's mesh.ply)"},
      {with_mesh(dir + "/garbage.ply"), "initial.mesh '" + dir + "/garbage.ply': cannot be read"},
      {with_mesh(dir + "/nan.ply"), "nan.ply"},
      {with_mesh(dir + "/no_faces.ply"), "no_faces.ply': has no faces"},
      {with_mesh(dir + "/inverted.ply"), "inverted.ply': its faces point down"},
      {no_crs, "initial.crs: initial.mesh '" + dir + "/no_crs.obj' does not say its CRS"},
  };
  for (const auto& [s, expected] : cases)
    EXPECT_NE(PlanError(s).find(expected), std::string::npos) << PlanError(s) << "\nexpected: " << expected;
  EXPECT_NE(PlanError(with_mesh(dir + "/nan.ply")).find("non-finite"), std::string::npos)
      << PlanError(with_mesh(dir + "/nan.ply"));

  JobSpec limited = with_mesh(scene_ + "/truth/mesh.ply");
  limited.initial_mesh.max_faces = 10;
  EXPECT_NE(PlanError(limited).find("faces, more than the limit of 10"), std::string::npos) << PlanError(limited);
  JobSpec wrong_crs = with_mesh(scene_ + "/truth/mesh.ply");
  wrong_crs.initial_mesh.crs = "EPSG:32618";  // the next UTM zone: 600 km east
  EXPECT_NE(PlanError(wrong_crs).find("outside the images' footprint"), std::string::npos) << PlanError(wrong_crs);
  JobSpec unknown_crs = with_mesh(scene_ + "/truth/mesh.ply");
  unknown_crs.initial_mesh.crs = "EPSG:99999999";
  EXPECT_NE(PlanError(unknown_crs).find("initial.crs: 'EPSG:99999999' is not a usable CRS"), std::string::npos);
  JobSpec elsewhere = with_mesh(scene_ + "/truth/mesh.ply");
  for (auto& p : elsewhere.aoi.polygon) p.x() += 5000;
  EXPECT_NE(PlanError(elsewhere).find("outside the aoi"), std::string::npos) << PlanError(elsewhere);
  // The no-CRS OBJ is fine once its CRS is given.
  JobSpec given = no_crs;
  given.initial_mesh.crs = "EPSG:32617";
  EXPECT_EQ(PlanError(given), "");
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

// Cells inside the AOI without a surface, away from its outer 2-cell band: a gap along a
// seam would be a line of them.
int InteriorHoles(const std::string& dsm_path) {
  const Dsm dsm = ReadDsm(dsm_path);
  int holes = 0;
  for (int row = 2; row < dsm.height - 2; ++row)
    for (int col = 2; col < dsm.width - 2; ++col) holes += !std::isfinite(dsm.at(col, row));
  return holes;
}

// The centre of the highest 4 m disc of the truth DSM flat within 0.2 m (a roof's
// middle: nothing above it, no wall near it), and its height.
Eigen::Vector3d FlatRoofSpot(const Dsm& truth) {
  const double cell = truth.geo_transform[1];
  const int r = int(std::ceil(4 / cell));
  Eigen::Vector3d best(0, 0, -1e9);
  for (int j = r; j < truth.height - r; j += 3)
    for (int i = r; i < truth.width - r; i += 3) {
      float lo = 1e9f, hi = -1e9f;
      for (int dj = -r; dj <= r; ++dj)
        for (int di = -r; di <= r; ++di)
          if (di * di + dj * dj <= r * r) {
            const float z = truth.at(i + di, j + dj);
            lo = std::min(lo, z), hi = std::max(hi, z);
          }
      if (std::isfinite(lo) && std::isfinite(hi) && hi - lo < 0.2f && hi > best.z())
        best = Eigen::Vector3d(truth.geo_transform[0] + (i + 0.5) * cell,
                               truth.geo_transform[3] - (j + 0.5) * cell, hi);
    }
  return best;
}

TEST_F(MeshJob, HolesInTheMeshAreFilledUpToTheLimit) {
  // The truth mesh without its faces within 2.5 m of a flat roof's middle: a gap the
  // images see through (a photogrammetric mesh's missing patch).
  const Eigen::Vector3d spot = FlatRoofSpot(ReadDsm(scene_ + "/truth/dsm.tif"));
  ASSERT_GT(spot.z(), -1e8) << "no flat roof in the tiny scene";
  TriangleMesh mesh = ReadMesh(scene_ + "/truth/mesh.ply");
  std::vector<Eigen::Vector3i> kept;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d c =
        (mesh.AbsoluteVertex(f[0]) + mesh.AbsoluteVertex(f[1]) + mesh.AbsoluteVertex(f[2])) / 3;
    if ((c.head<2>() - spot.head<2>()).norm() > 2.5 || std::abs(c.z() - spot.z()) > 1) kept.push_back(f);
  }
  ASSERT_LT(kept.size(), mesh.faces.size());
  mesh.faces = kept;
  const std::string dir = OutDir("holed_mesh");
  fs::create_directories(dir);
  WriteMesh(dir + "/holed.ply", mesh);
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.initial_mesh.path = dir + "/holed.ply";
  spec.aoi.polygon = SceneAoi();
  const std::string filled_dir = OutDir("holes_filled");
  const JobOutputs filled = RunJob(spec, filled_dir);  // fill_holes_m 50 m
  spec.fill_holes_m = 0;
  const JobOutputs open = RunJob(spec, OutDir("holes_open"));
  ASSERT_EQ(filled.assembly.tiles_failed, 0);
  ASSERT_EQ(open.assembly.tiles_failed, 0);
  // Open: the roof's hole shows in the DSM (a 1.5 m disc is ~80 cells), or the ground
  // far below it; filled: the roof is whole again, at its height.
  const Dsm open_dsm = ReadDsm(open.dsm_path), filled_dsm = ReadDsm(filled.dsm_path);
  int open_gap = 0, filled_gap = 0, cells = 0;
  for (int j = 0; j < filled_dsm.height; ++j)
    for (int i = 0; i < filled_dsm.width; ++i) {
      const Eigen::Vector2d p(filled_dsm.geo_transform[0] + (i + 0.5) * filled_dsm.geo_transform[1],
                              filled_dsm.geo_transform[3] + (j + 0.5) * filled_dsm.geo_transform[5]);
      if ((p - spot.head<2>()).norm() > 1.5) continue;
      ++cells;
      open_gap += !(std::abs(open_dsm.at(i, j) - spot.z()) < 0.5);
      filled_gap += !(std::abs(filled_dsm.at(i, j) - spot.z()) < 0.5);
    }
  EXPECT_GT(cells, 50);
  EXPECT_GT(open_gap, cells / 2);
  EXPECT_EQ(filled_gap, 0);
  ExpectNoDebris(filled_dir);
}

TEST_F(MeshJob, ChainingAResultIsStable) {
  JobSpec first = Spec();
  first.tiling.tile_size_m = 18;
  const std::string out_a = OutDir("chain_a"), out_b = OutDir("chain_b");
  const JobOutputs a = RunJob(first, out_a);
  ASSERT_EQ(a.assembly.tiles_failed, 0);
  JobSpec second = first;
  second.initial_dsm.clear();
  second.initial_mesh.path = out_a + "/";  // the result directory: its mesh.ply
  second.aoi.polygon = SceneAoi();
  const JobOutputs b = RunJob(second, out_b);
  ASSERT_EQ(b.assembly.tiles_failed, 0);
  ExpectNoDebris(out_b);
  const std::string truth = scene_ + "/truth/dsm.tif";
  const double error_a = MedianAbsDsmError(a.dsm_path, truth), error_b = MedianAbsDsmError(b.dsm_path, truth);
  EXPECT_LT(error_b, error_a * 1.02 + 0.005) << "first " << error_a << " m, chained " << error_b << " m";
  EXPECT_LT(InteriorHoles(b.dsm_path), ReadDsm(b.dsm_path).width / 4);
  EXPECT_EQ(b.assembly.seams.size(), 4u);
  EXPECT_LT(b.assembly.seams_total.median_abs_m, 0.15);
}

TEST_F(MeshJob, AMeshInEcefOrGeographicCoordinatesGivesTheSameResult) {
  JobSpec spec = Spec();
  spec.initial_dsm.clear();
  spec.aoi.polygon = SceneAoi();
  spec.aoi.crs = "EPSG:32617";
  spec.output_crs = "EPSG:32617";
  spec.dsm_resolution_m = 0.3;  // the same grid (the GSD is taken at the mesh's centre)
  spec.refine.iterations_per_level = 1;
  spec.initial_mesh.path = scene_ + "/truth/mesh.ply";
  const JobOutputs utm = RunJob(spec, OutDir("crs_utm"));
  const TriangleMesh truth = ReadMesh(scene_ + "/truth/mesh.ply");
  for (const char* crs : {"EPSG:4978", "EPSG:4326"}) {
    std::vector<Eigen::Vector3d> points(truth.num_vertices());
    for (size_t i = 0; i < points.size(); ++i) points[i] = truth.AbsoluteVertex(i);
    CrsTransform(truth.crs, crs).Apply(&points);
    TriangleMesh moved = truth;
    moved.crs = crs;
    moved.origin = points[0].array().round().matrix();
    for (size_t i = 0; i < points.size(); ++i) moved.vertices[i] = (points[i] - moved.origin).cast<float>();
    const std::string dir = OutDir(std::string("crs_") + (crs[5] == '4' && crs[8] == '7' ? "ecef" : "geo"));
    fs::create_directories(dir);
    JobSpec other = spec;
    other.initial_mesh.path = dir + "/mesh_in.ply";
    WriteMesh(other.initial_mesh.path, moved);
    const JobOutputs o = RunJob(other, dir + "/out");
    EXPECT_EQ(o.plan.dsm.geo_transform, utm.plan.dsm.geo_transform) << crs;
    ASSERT_EQ(o.tiles.size(), utm.tiles.size()) << crs;
    EXPECT_NEAR(double(o.assembly.faces), double(utm.assembly.faces), 0.02 * utm.assembly.faces) << crs;
    const std::string truth_dsm = scene_ + "/truth/dsm.tif";
    EXPECT_NEAR(MedianAbsDsmError(o.dsm_path, truth_dsm), MedianAbsDsmError(utm.dsm_path, truth_dsm), 0.01) << crs;
  }
}

}  // namespace
}  // namespace satmesh

namespace satmesh {
namespace {

TEST_F(MeshJob, WithADsmTooTheDsmFillsWhereTheMeshHasNoSurface) {
  // The truth mesh's west half, and the initial DSM.
  const TriangleMesh truth = ReadMesh(scene_ + "/truth/mesh.ply");
  PointMesh west;
  for (size_t i = 0; i < truth.num_vertices(); ++i) west.points.push_back(truth.AbsoluteVertex(i));
  west.faces = truth.faces;
  const auto aoi = SceneAoi();
  const double x_mid = 0.5 * (aoi[0].x() + aoi[1].x());
  west = ClipToBox(west, Box2d{aoi[0].x() - 100, aoi[0].y() - 100, x_mid, aoi[2].y() + 100});
  TriangleMesh half;
  half.crs = truth.crs;
  half.origin = truth.origin;
  half.faces = west.faces;
  for (const auto& p : west.points) half.vertices.push_back((p - half.origin).cast<float>());
  const std::string dir = OutDir("mesh_and_dsm");
  fs::create_directories(dir);
  WriteMesh(dir + "/west.ply", half);

  JobSpec spec = Spec();  // keeps initial.dsm: the plan is on its grid
  spec.initial_mesh.path = dir + "/west.ply";
  const JobPlan plan = PlanJob(spec);
  ASSERT_EQ(plan.tiles.size(), 1u);
  const TileInput input = PrepareTileInput(spec, plan, 0);
  const size_t cells = input.initial_heights.z.size();
  size_t empty = 0, west_cells = 0, west_match = 0;
  const Dsm truth_dsm = ReadDsm(scene_ + "/truth/dsm.tif");
  for (int j = 0; j < input.initial_heights.height; ++j)
    for (int i = 0; i < input.initial_heights.width; ++i) {
      const float z = input.initial_heights.at(i, j);
      empty += !std::isfinite(z);
      const double x = input.initial_heights.geo_transform[0] + (i + 0.5) * input.initial_heights.geo_transform[1];
      if (x < x_mid - 1) {  // the mesh's half: the truth's heights, not the DSM's
        const double y = input.initial_heights.geo_transform[3] + (j + 0.5) * input.initial_heights.geo_transform[5];
        const int ti = int((x - truth_dsm.geo_transform[0]) / truth_dsm.geo_transform[1]);
        const int tj = int((y - truth_dsm.geo_transform[3]) / truth_dsm.geo_transform[5]);
        if (ti < 0 || tj < 0 || ti >= truth_dsm.width || tj >= truth_dsm.height || !std::isfinite(z)) continue;
        ++west_cells;
        west_match += std::abs(z - truth_dsm.at(ti, tj)) < 0.05;
      }
    }
  EXPECT_LT(empty, cells / 50) << "the DSM did not fill the east half";
  EXPECT_GT(input.filled_dsm_cells, cells / 3);  // about the east half (+ overlap)
  EXPECT_LT(input.filled_dsm_cells, cells * 2 / 3);
  EXPECT_GT(west_match, west_cells * 9 / 10);
}

}  // namespace
}  // namespace satmesh
