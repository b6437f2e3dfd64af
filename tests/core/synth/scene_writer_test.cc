// End to end: a tiny scene directory and its contracts.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "core/dsm/dsm.h"
#include "core/image/acquisition_info.h"
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
  ASSERT_EQ(o.views.acquisition, Acquisition::kTriStereo);  // the small preset's collection
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
  EXPECT_EQ(scene["acquisition"], "tristereo");
  // One pass: one sun, the same date; no RPC bias within a pass.
  EXPECT_EQ(scene["views"][0]["sun"], scene["views"][2]["sun"]);
  EXPECT_EQ(scene["views"][0]["pass"], scene["views"][2]["pass"]);
  EXPECT_EQ(std::string(scene["views"][0]["acquisition_time"]).substr(0, 10),
            std::string(scene["views"][2]["acquisition_time"]).substr(0, 10));
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
    EXPECT_EQ(v.bias_col_row_px, Eigen::Vector2d::Zero());
    // The acquisition metadata as GDAL exposes a WorldView IMD, read back from the file.
    const AcquisitionInfo acq = ReadAcquisitionInfo(dir + "/" + v.image);
    EXPECT_NEAR(*acq.sun_elevation_deg, v.sun.elevation_deg, 1e-5);
    EXPECT_NEAR(*acq.sun_azimuth_deg, v.sun.azimuth_deg, 1e-5);
    EXPECT_NEAR(*acq.off_nadir_deg, v.off_nadir_deg, 1e-5);
    EXPECT_NEAR(*acq.satellite_azimuth_deg, v.azimuth_deg, 1e-5);
    EXPECT_NEAR(*acq.satellite_elevation_deg, 90 - v.zenith_deg, 1e-5);
    EXPECT_NEAR(*acq.acquisition_unix_s, v.acquisition_unix_s, 1e-5);
  }
  EXPECT_GT(r.num_roof_cells, 0u);
  std::filesystem::remove_all(dir);
}

// Multi-date: each view under its own date's sun, each image's RPC biased like a vendor's.
TEST(GenerateScene, TinyMultiDateSceneHasPerViewSunsAndBiases) {
  SynthOptions o = SynthPreset("small", 4);
  SetAcquisition(&o, Acquisition::kMultiDate);
  o.views.num_views = 3;
  o.city.aoi_size_m = 36;
  o.city.ground_margin_m = 45;
  o.city.building_margin_m = 5;
  o.city.street_pitch_m = 40;
  o.render.supersample = 1;
  o.write_preview = false;
  const std::string dir = (std::filesystem::temp_directory_path() / "synth_tiny_multidate").string();
  std::filesystem::remove_all(dir);
  const SynthResult r = GenerateScene(dir, o);
  ASSERT_EQ(r.views.size(), 3u);
  std::set<double> sun_elevations, times;
  for (const auto& v : r.views) {
    EXPECT_GT(v.bias_col_row_px.norm(), 0.0);
    EXPECT_LT(v.bias_col_row_px.norm(), 6.0);  // sigma 1 px per axis
    sun_elevations.insert(v.sun.elevation_deg);
    times.insert(v.acquisition_unix_s);
    const AcquisitionInfo acq = ReadAcquisitionInfo(dir + "/" + v.image);
    EXPECT_NEAR(*acq.sun_elevation_deg, v.sun.elevation_deg, 1e-5);
  }
  EXPECT_EQ(sun_elevations.size(), 3u);
  EXPECT_EQ(times.size(), 3u);
  std::ifstream in(std::filesystem::path(dir) / "job.json");
  const nlohmann::json job = nlohmann::json::parse(in);
  EXPECT_FALSE(job.contains("options"));  // biased RPCs: the bias estimation stays on
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace satmesh::synth
