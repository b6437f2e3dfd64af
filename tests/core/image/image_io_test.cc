#include "core/image/image_io.h"

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "core/common/error.h"
#include "tests/scratch_dir.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path dir = fs::temp_directory_path() /
                       ("satmesh_image_io_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  testing::RemoveAtExit(dir);
  return dir;
}

// A w x h GeoTIFF whose band b pixel (c, r) holds 1000*b + 10*r + c.
std::string MakeTiff(const std::string& name, GDALDataType type, int w, int h, int bands) {
  GDALAllRegister();
  const std::string path = (TempDir() / name).string();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  GDALDataset* ds = driver->Create(path.c_str(), w, h, bands, type, nullptr);
  for (int b = 1; b <= bands; ++b) {
    std::vector<float> values(size_t(w) * h);
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c) values[size_t(r) * w + c] = float(1000 * b + 10 * r + c);
    EXPECT_EQ(ds->GetRasterBand(b)->RasterIO(GF_Write, 0, 0, w, h, values.data(), w, h,
                                             GDT_Float32, 0, 0, nullptr),
              CE_None);
  }
  GDALClose(ds);
  return path;
}

TEST(ReadRasterInfo, ReportsSizeBandsAndType) {
  const RasterInfo info = ReadRasterInfo(MakeTiff("info.tif", GDT_UInt16, 7, 5, 2));
  EXPECT_EQ(info.width, 7);
  EXPECT_EQ(info.height, 5);
  EXPECT_EQ(info.bands, 2);
  EXPECT_EQ(info.data_type, "UInt16");
}

TEST(ReadRasterInfo, MissingFileIsNotFound) {
  try {
    ReadRasterInfo("/nonexistent/satmesh.tif");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kNotFound);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/satmesh.tif"), std::string::npos);
  }
}

TEST(ReadImageWindow, UInt16WindowInside) {
  const std::string path = MakeTiff("u16.tif", GDT_UInt16, 8, 6, 2);
  const ImageF image = ReadImageWindow(path, 2, PixelWindow{2, 1, 3, 4});
  ASSERT_EQ(image.width, 3);
  ASSERT_EQ(image.height, 4);
  EXPECT_EQ(image.at(0, 0), 2000.f + 10 * 1 + 2);
  EXPECT_EQ(image.at(2, 3), 2000.f + 10 * 4 + 4);
}

TEST(ReadImageWindow, Float32WindowPartlyOutsideIsFilled) {
  const std::string path = MakeTiff("f32.tif", GDT_Float32, 5, 4, 1);
  const ImageF image = ReadImageWindow(path, 1, PixelWindow{-2, 2, 4, 4}, /*fill=*/-7.f);
  ASSERT_EQ(image.width, 4);
  EXPECT_EQ(image.at(0, 0), -7.f);             // col -2
  EXPECT_EQ(image.at(1, 1), -7.f);             // col -1
  EXPECT_EQ(image.at(2, 0), 1000.f + 20 + 0);  // col 0, row 2
  EXPECT_EQ(image.at(3, 1), 1000.f + 30 + 1);  // col 1, row 3
  EXPECT_EQ(image.at(3, 2), -7.f);             // row 4 is outside
  const ImageF outside = ReadImageWindow(path, 1, PixelWindow{10, 10, 2, 2}, 3.f);
  EXPECT_EQ(outside.at(1, 1), 3.f);
}

TEST(ReadImageWindow, BadBandNamesFileBandAndWindow) {
  const std::string path = MakeTiff("band.tif", GDT_Float32, 3, 3, 1);
  try {
    ReadImageWindow(path, 3, PixelWindow{0, 0, 2, 2});
    FAIL();
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("band 3"), std::string::npos) << msg;
    EXPECT_NE(msg.find("width 2"), std::string::npos) << msg;
  }
  EXPECT_THROW(ReadImageWindow(path, 1, PixelWindow{0, 0, 0, 2}), Error);
}

TEST(ReadImage, ReadsWholeBand) {
  const ImageF image = ReadImage(MakeTiff("whole.tif", GDT_UInt16, 4, 3, 1));
  ASSERT_EQ(image.width, 4);
  ASSERT_EQ(image.height, 3);
  EXPECT_EQ(image.at(3, 2), 1000.f + 23);
}

TEST(WritePng, WritesReadableEightBitImage) {
  ImageF image(4, 2);
  for (int i = 0; i < 8; ++i) image.pixels[i] = float(i);
  const std::string path = (TempDir() / "preview.png").string();
  WritePng(path, image, 0.f, 7.f);
  const ImageF back = ReadImage(path);
  ASSERT_EQ(back.width, 4);
  EXPECT_EQ(back.at(0, 0), 0.f);
  EXPECT_EQ(back.at(3, 1), 255.f);
  EXPECT_THROW(WritePng(path, image, 1.f, 1.f), Error);
  EXPECT_THROW(WritePng("/nonexistent/dir/x.png", image, 0.f, 1.f), Error);
}

}  // namespace
}  // namespace satmesh
