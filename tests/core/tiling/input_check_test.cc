// Bad input data, each refused before any tile runs with a message naming the job's field,
// the file and what is wrong (issue 23). Real GeoTIFFs through GDAL: a tiny synthetic
// scene (generated once, ~2 s) and broken copies of its files.
#include "core/tiling/input_check.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include <unistd.h>

#include "core/common/error.h"
#include "core/dsm/dsm.h"
#include "core/geo/crs.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"
#include "core/synth/scene_files.h"
#include "core/synth/scene_writer.h"
#include "proto/job_spec_json.h"
#include "tests/scratch_dir.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

class BadInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    synth::SynthOptions o = synth::SynthPreset("small", 3);
    o.city.aoi_size_m = 24;
    o.city.ground_margin_m = 20;
    o.city.building_margin_m = 4;
    o.city.street_pitch_m = 40;
    o.render.supersample = 1;
    o.write_preview = false;
    scene_ = (fs::temp_directory_path() / ("bad_input_scene_" + std::to_string(::getpid()))).string();
    fs::remove_all(scene_);
    synth::GenerateScene(scene_, o);
    testing::RemoveAtExit(scene_);
  }

  static JobSpec Spec() { return proto::ReadJobFile(scene_ + "/job.json"); }
  static std::string Scratch(const std::string& name) { return scene_ + "/bad_" + name; }

  // The error CheckJobInputs (after PlanJob) throws for `spec`, "" when it passes.
  static std::string Refusal(const JobSpec& spec, ErrorCode* code = nullptr) {
    try {
      CheckJobInputs(spec, PlanJob(spec));
      return "";
    } catch (const Error& e) {
      if (code) *code = e.code();
      return e.what();
    }
  }

  // A GeoTIFF of width x height UInt16 pixels, value 1000, with the given RPC keys (none
  // when empty).
  static std::string WriteImage(const std::string& name, int width, int height,
                                const std::map<std::string, std::string>& rpc) {
    const std::string path = Scratch(name);
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
    GDALDataset* ds = driver->Create(path.c_str(), width, height, 1, GDT_UInt16, nullptr);
    std::vector<uint16_t> px(size_t(width) * height, 1000);
    EXPECT_EQ(ds->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, width, height, px.data(), width, height,
                                              GDT_UInt16, 0, 0, nullptr), CE_None);
    char** md = nullptr;
    for (const auto& [k, v] : rpc) md = CSLSetNameValue(md, k.c_str(), v.c_str());
    if (md) ds->SetMetadata(md, "RPC");
    CSLDestroy(md);
    GDALClose(GDALDataset::ToHandle(ds));
    return path;
  }
  static std::map<std::string, std::string> RpcOf(int image,
                                                  const std::function<void(RpcCoefficients&)>& edit = {}) {
    RpcCoefficients c = ReadRpc(Spec().images[image].path).coefficients();
    if (edit) edit(c);
    return RpcModel::FromCoefficients(c).ToKeyValues();
  }
  static std::string WriteDsmCopy(const std::string& name, const std::function<void(Dsm&)>& edit) {
    Dsm dsm = ReadDsm(Spec().initial_dsm);
    edit(dsm);
    const std::string path = Scratch(name);
    WriteDsm(path, dsm);
    return path;
  }

  static std::string scene_;
};
std::string BadInput::scene_;

#define EXPECT_CONTAINS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << (text)

TEST_F(BadInput, TheSceneItselfPasses) { EXPECT_EQ(Refusal(Spec()), ""); }

TEST_F(BadInput, TruncatedTiffIsNamed) {
  JobSpec spec = Spec();
  const std::string path = Scratch("truncated.tif");
  fs::copy_file(spec.images[1].path, path, fs::copy_options::overwrite_existing);
  fs::resize_file(path, fs::file_size(path) / 2);
  spec.images[1].path = path;
  ErrorCode code{};
  const std::string message = Refusal(spec, &code);
  EXPECT_EQ(code, ErrorCode::kInvalidInput);
  EXPECT_CONTAINS(message, "images[1].href: '" + path + "'");
  EXPECT_CONTAINS(message, "cannot be read (truncated or corrupt file?)");
}

TEST_F(BadInput, CorruptTiffHeaderIsNamed) {
  JobSpec spec = Spec();
  const std::string path = Scratch("corrupt.tif");
  std::ofstream(path, std::ios::binary) << "II*\0garbage that is no TIFF directory at all";
  spec.images[0].path = path;
  ErrorCode code{};
  const std::string message = Refusal(spec, &code);
  EXPECT_EQ(code, ErrorCode::kInvalidInput);
  EXPECT_CONTAINS(message, "images[0].href: '" + path + "' is not a readable raster");
}

TEST_F(BadInput, ImageWithoutRpcIsNamed) {
  JobSpec spec = Spec();
  spec.images[2].path = WriteImage("no_rpc.tif", 200, 200, {});
  const std::string message = Refusal(spec);
  EXPECT_CONTAINS(message, "images[2].href: image '" + spec.images[2].path + "' has no RPC");
}

TEST_F(BadInput, RpcPuttingTheAoiOutsideTheImageIsNamed) {
  JobSpec spec = Spec();
  const RasterInfo info = ReadRasterInfo(spec.images[0].path);
  spec.images[0].path = WriteImage("shifted_rpc.tif", info.width, info.height,
                                   RpcOf(0, [](RpcCoefficients& c) { c.samp_off += 50000; }));
  const std::string message = Refusal(spec);
  EXPECT_CONTAINS(message, "images[0].href: '" + spec.images[0].path + "': its RPC puts the AOI outside the image");
  EXPECT_CONTAINS(message, "of a " + std::to_string(info.width) + "x" + std::to_string(info.height) + " image");
}

TEST_F(BadInput, ImageOfAnotherPlaceIsNamed) {
  JobSpec spec = Spec();
  const RasterInfo info = ReadRasterInfo(spec.images[1].path);
  // The same camera 2 degrees of latitude to the north: ~222 km away.
  spec.images[1].path = WriteImage("elsewhere.tif", info.width, info.height,
                                   RpcOf(1, [](RpcCoefficients& c) { c.lat_off += 2.0; }));
  const std::string message = Refusal(spec);
  EXPECT_CONTAINS(message, "images[1].href: '" + spec.images[1].path + "' is an image of another place");
  const size_t at = message.find(" km away");
  ASSERT_NE(at, std::string::npos) << message;
  const double km = std::stod(message.substr(message.rfind('(', at) + 1));
  EXPECT_NEAR(km, 222.4, 1.0);
}

TEST_F(BadInput, OneByOneImageIsNamed) {
  JobSpec spec = Spec();
  spec.images[0].path = WriteImage("one_pixel.tif", 1, 1, RpcOf(0));
  const std::string message = Refusal(spec);
  EXPECT_CONTAINS(message, "images[0].href: '" + spec.images[0].path + "' is 1x1 pixels; an image needs at least 16x16");
}

TEST_F(BadInput, TheSameImageTwiceIsNamed) {
  JobSpec spec = Spec();
  spec.images.push_back(spec.images[0]);
  EXPECT_CONTAINS(Refusal(spec), "images[3].href: '" + spec.images[0].path + "' is the same file as images[0].href");
  // A copy under another name (or a link): the same RPC and size.
  const std::string copy = Scratch("copy.tif");
  fs::copy_file(spec.images[0].path, copy, fs::copy_options::overwrite_existing);
  spec.images[3].path = copy;
  EXPECT_CONTAINS(Refusal(spec), "images[3].href: '" + copy + "' has the same RPC and size as images[0].href");
}

TEST_F(BadInput, DsmAllNodataIsNamed) {
  JobSpec spec = Spec();
  spec.initial_dsm = WriteDsmCopy("nan_dsm.tif", [](Dsm& d) { std::fill(d.z.begin(), d.z.end(), NAN); });
  const Dsm dsm = ReadDsm(spec.initial_dsm);
  const std::string message = Refusal(spec);
  EXPECT_CONTAINS(message, "initial.dsm: '" + spec.initial_dsm + "': all " +
                               std::to_string(dsm.width * dsm.height) + " cells of the AOI are nodata");
  // With a nodata value instead of NaN.
  const std::string path = Scratch("nodata_dsm.tif");
  GDALDataset* ds = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(
      path.c_str(), dsm.width, dsm.height, 1, GDT_Float32, nullptr);
  double gt[6];
  std::copy(dsm.geo_transform.begin(), dsm.geo_transform.end(), gt);
  ds->SetGeoTransform(gt);
  ds->SetProjection(dsm.crs_wkt.c_str());
  ds->GetRasterBand(1)->SetNoDataValue(-9999);
  ds->GetRasterBand(1)->Fill(-9999);
  GDALClose(GDALDataset::ToHandle(ds));
  spec.initial_dsm = path;
  EXPECT_CONTAINS(Refusal(spec), "cells of the AOI are nodata (nodata value -9999.000)");
}

TEST_F(BadInput, DsmInAGeographicCrsIsNamed) {
  JobSpec spec = Spec();
  spec.initial_dsm = WriteDsmCopy("geographic_dsm.tif", [](Dsm& d) {
    d.crs_wkt = CrsToWkt("EPSG:4326");
    d.geo_transform = {-81.66, 1e-5, 0, 30.33, 0, -1e-5};
  });
  ErrorCode code{};
  const std::string message = Refusal(spec, &code);
  EXPECT_EQ(code, ErrorCode::kInvalidInput);
  EXPECT_CONTAINS(message, "initial.dsm: '" + spec.initial_dsm + "' is in a geographic CRS (degrees)");
}

TEST_F(BadInput, HeightsInFeetAreNamed) {
  JobSpec spec = Spec();
  spec.initial_dsm = WriteDsmCopy("feet_dsm.tif", [](Dsm& d) { for (float& z : d.z) z *= 3.28084f; });
  {
    GDALDataset* ds = GDALDataset::Open(spec.initial_dsm.c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE);
    ASSERT_NE(ds, nullptr);
    ds->GetRasterBand(1)->SetUnitType("ft");
    GDALClose(GDALDataset::ToHandle(ds));
  }
  EXPECT_CONTAINS(Refusal(spec), "initial.dsm: '" + spec.initial_dsm + "': heights are in feet (band unit 'ft')");
  // A compound CRS whose vertical part is in feet (UTM 17N + NAVD88 height (ftUS)): GDAL
  // gives the band the vertical CRS's unit.
  spec.initial_dsm = WriteDsmCopy("feet_vertical_dsm.tif", [](Dsm& d) { d.crs_wkt = CrsToWkt("EPSG:32617+6360"); });
  EXPECT_CONTAINS(Refusal(spec), "initial.dsm: '" + spec.initial_dsm +
                                     "': heights are in feet (band unit 'US survey foot')");
  // A projected CRS in feet (NY Long Island, ftUS): x/y in feet too.
  spec.initial_dsm = WriteDsmCopy("feet_xy_dsm.tif", [](Dsm& d) { d.crs_wkt = CrsToWkt("EPSG:2263"); });
  EXPECT_CONTAINS(Refusal(spec), "initial.dsm: '" + spec.initial_dsm + "': the CRS's x/y are in US survey foot");
}

}  // namespace
}  // namespace satmesh
