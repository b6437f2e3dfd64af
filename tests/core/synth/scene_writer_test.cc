// End to end: a tiny scene directory and its contracts.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/dsm/dsm.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"
#include "core/synth/scene_writer.h"

namespace satmesh::synth {
namespace {

TEST(GenerateScene, TinySceneFollowsTheLayout) {
  SynthOptions o = SynthPreset("small", 2);
  o.city.aoi_size_m = 36;
  o.city.ground_margin_m = 45;
  o.city.building_margin_m = 5;
  o.city.street_pitch_m = 40;
  o.num_views = 3;
  o.render.supersample = 1;
  const std::string dir = (std::filesystem::temp_directory_path() / "synth_tiny_scene").string();
  std::filesystem::remove_all(dir);
  const SynthResult r = GenerateScene(dir, o);
  for (const char* f : {"scene.json", "job.json", "preview.png", "truth/mesh.ply", "truth/dsm.tif",
                        "truth/roof_mask.tif", "truth/facade_points.ply", "initial/dsm.tif",
                        "images/img_00.tif", "images/img_02.tif"})
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(dir) / f)) << f;
  std::ifstream in(std::filesystem::path(dir) / "scene.json");
  const nlohmann::json scene = nlohmann::json::parse(in);
  EXPECT_EQ(scene["crs"], "EPSG:32617");
  EXPECT_EQ(scene["views"].size(), 3u);
  EXPECT_LT(double(scene["views"][0]["rpc_fit_max_px"]), 0.01);
  const Dsm truth = ReadDsm(dir + "/truth/dsm.tif");
  EXPECT_EQ(truth.width, 120);
  const double hmin = scene["height_range_m"][0], hmax = scene["height_range_m"][1];
  EXPECT_GT(hmin, -40);
  EXPECT_LT(hmax, 50);
  for (const auto& v : r.views) {
    EXPECT_LT(v.rpc_fit_max_half_step_px, 0.01);
    EXPECT_LT(v.ray_grid_error_px, 0.01);
    const ImageF img = ReadImage(dir + "/" + v.image);
    float hi = 0;
    for (float p : img.pixels) hi = std::max(hi, p);
    EXPECT_LE(hi, 2047.f);
    EXPECT_GT(hi, 200.f);
    // The AOI centre projects inside the image through the file's RPC.
    const RpcModel rpc = ReadRpc(dir + "/" + v.image);
    const Eigen::Vector3d geo = v.camera.LocalizeAtHeight(
        Eigen::Vector2d(v.camera.params().col_center, v.camera.params().row_center), hmin).value();
    EXPECT_LT((rpc.PixelFromGeo(geo) - *v.camera.PixelFromGeo(geo)).norm(), 0.01);
  }
  EXPECT_GT(r.num_roof_cells, 0u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace satmesh::synth
