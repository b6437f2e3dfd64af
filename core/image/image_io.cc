#include "core/image/image_io.h"

#include <cpl_vsi.h>
#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/common/error.h"
#include "core/common/gdal_init.h"

namespace satmesh {
namespace {

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

std::string LastGdalMessage() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg && *msg) ? std::string(": ") + msg : std::string();
}

DatasetPtr OpenRaster(const std::string& path) {
  EnsureGdalInitialized();
  VSIStatBufL stat;
  const bool is_virtual = path.rfind("/vsi", 0) == 0;
  if (!is_virtual && VSIStatL(path.c_str(), &stat) != 0)
    ThrowError(ErrorCode::kNotFound, "raster not found: " + path);
  CPLErrorReset();
  DatasetPtr ds(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  SATMESH_CHECK(ds != nullptr, ErrorCode::kIo,
                "cannot open raster " + path + LastGdalMessage());
  return ds;
}

// GDAL reads a whole block per band (for pixel-interleaved files, all bands' samples at
// once) before copying the window out: a 1 KB header declaring 12,000 bands of 256x256
// floats made it allocate 3 GB (found by fuzz_geotiff). Real images stay far below.
constexpr double kMaxBlockBytes = 256.0 * (1 << 20);

void CheckBlockSize(GDALDataset& ds, const std::string& path) {
  if (ds.GetRasterCount() < 1) return;
  int bx = 0, by = 0;
  GDALRasterBand* band = ds.GetRasterBand(1);
  band->GetBlockSize(&bx, &by);
  const char* interleave = ds.GetMetadataItem("INTERLEAVE", "IMAGE_STRUCTURE");
  const int samples = interleave && std::string(interleave) == "PIXEL" ? ds.GetRasterCount() : 1;
  const double bytes = double(bx) * by * samples * GDALGetDataTypeSizeBytes(band->GetRasterDataType());
  SATMESH_CHECK(bytes <= kMaxBlockBytes, ErrorCode::kInvalidInput,
                "raster " + path + ": one block of " + std::to_string(bx) + "x" + std::to_string(by) +
                    " pixels x " + std::to_string(samples) + " interleaved bands is " +
                    std::to_string(int64_t(bytes / (1 << 20))) + " MB (at most " +
                    std::to_string(int(kMaxBlockBytes / (1 << 20))) + " MB is read at once)");
}

std::string WindowText(const PixelWindow& w) {
  return "window (col0 " + std::to_string(w.col0) + ", row0 " + std::to_string(w.row0) +
         ", width " + std::to_string(w.width) + ", height " + std::to_string(w.height) + ")";
}

}  // namespace

RasterInfo ReadRasterInfo(const std::string& path) {
  DatasetPtr ds = OpenRaster(path);
  RasterInfo info;
  info.width = ds->GetRasterXSize();
  info.height = ds->GetRasterYSize();
  info.bands = ds->GetRasterCount();
  if (info.bands > 0)
    info.data_type = GDALGetDataTypeName(ds->GetRasterBand(1)->GetRasterDataType());
  return info;
}

std::string RasterDriverName(const std::string& path) {
  EnsureGdalInitialized();
  CPLErrorReset();
  GDALDriverH driver = GDALIdentifyDriverEx(path.c_str(), GDAL_OF_RASTER, nullptr, nullptr);
  return driver ? GDALGetDriverShortName(driver) : "";
}

AcquisitionInfo ReadAcquisitionInfo(const std::string& path) {
  DatasetPtr ds = OpenRaster(path);
  MetadataList items;
  // The parser keeps the first item of a name (IMAGE_1 before other images): the IMD domain
  // first, then the default domain, then IMAGERY.
  for (const char* domain : {"IMD", "", "IMAGERY"}) {
    CSLConstList md = ds->GetMetadata(domain);
    for (int k = 0; md && md[k]; ++k) {
      char* key = nullptr;
      const char* value = CPLParseNameValue(md[k], &key);
      if (key && value) items.emplace_back(key, value);
      CPLFree(key);
    }
  }
  return AcquisitionInfoFromMetadata(items);
}

ImageF ReadImageWindow(const std::string& path, int band, const PixelWindow& window,
                       float fill) {
  const std::string where = path + " band " + std::to_string(band) + " " + WindowText(window);
  SATMESH_CHECK(window.width > 0 && window.height > 0, ErrorCode::kInvalidArgument,
                "empty read window: " + where);
  DatasetPtr ds = OpenRaster(path);
  SATMESH_CHECK(band >= 1 && band <= ds->GetRasterCount(), ErrorCode::kInvalidArgument,
                "band out of range (raster has " + std::to_string(ds->GetRasterCount()) +
                    " bands): " + where);
  CheckBlockSize(*ds, path);
  ImageF image(window.width, window.height, fill);
  // Intersection of the window with the raster, in raster pixels.
  const int c0 = std::max(window.col0, 0), r0 = std::max(window.row0, 0);
  const int c1 = std::min<long long>((long long)window.col0 + window.width, ds->GetRasterXSize());
  const int r1 = std::min<long long>((long long)window.row0 + window.height, ds->GetRasterYSize());
  if (c1 <= c0 || r1 <= r0) return image;  // entirely outside: all fill
  float* dst = &image.at(c0 - window.col0, r0 - window.row0);
  CPLErrorReset();
  const CPLErr err = ds->GetRasterBand(band)->RasterIO(
      GF_Read, c0, r0, c1 - c0, r1 - r0, dst, c1 - c0, r1 - r0, GDT_Float32,
      /*nPixelSpace=*/sizeof(float), /*nLineSpace=*/GSpacing(sizeof(float)) * window.width,
      nullptr);
  SATMESH_CHECK(err == CE_None, ErrorCode::kIo, "read failed: " + where + LastGdalMessage());
  return image;
}

ImageF ReadImage(const std::string& path, int band) {
  const RasterInfo info = ReadRasterInfo(path);
  return ReadImageWindow(path, band, PixelWindow{0, 0, info.width, info.height});
}

void WritePng(const std::string& path, const ImageF& image, float lo, float hi) {
  SATMESH_CHECK(!image.empty(), ErrorCode::kInvalidArgument, "WritePng: empty image for " + path);
  SATMESH_CHECK(hi > lo, ErrorCode::kInvalidArgument,
                "WritePng: need hi > lo, got [" + std::to_string(lo) + ", " +
                    std::to_string(hi) + "] for " + path);
  cv::Mat gray(image.height, image.width, CV_8U);
  const float scale = 255.f / (hi - lo);
  for (int r = 0; r < image.height; ++r) {
    auto* row = gray.ptr<unsigned char>(r);
    for (int c = 0; c < image.width; ++c) {
      const float v = image.at(c, r);
      row[c] = std::isfinite(v) ? cv::saturate_cast<unsigned char>((v - lo) * scale) : 0;
    }
  }
  bool ok = false;
  try {
    ok = cv::imwrite(path, gray);
  } catch (const cv::Exception& e) {
    ThrowError(ErrorCode::kIo, "cannot write PNG " + path + ": " + e.what());
  }
  SATMESH_CHECK(ok, ErrorCode::kIo, "cannot write PNG " + path);
}

}  // namespace satmesh
