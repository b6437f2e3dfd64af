#include "core/dsm/fill_holes.h"

#include <cpl_string.h>
#include <gdal_alg.h>
#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "core/common/error.h"

namespace satmesh {
namespace {

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

DatasetPtr MemDataset(int width, int height, GDALDataType type) {
  GDALAllRegister();
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  SATMESH_CHECK(mem != nullptr, ErrorCode::kInternal, "GDAL's MEM driver is missing");
  DatasetPtr d(mem->Create("", width, height, 1, type, nullptr));
  SATMESH_CHECK(d != nullptr, ErrorCode::kInternal, "GDAL: cannot create a MEM raster");
  return d;
}

// 255 for the cells inside the convex hull of the valid cells, else 0.
cv::Mat HullMask(const Dsm& dsm) {
  std::vector<cv::Point> ends;  // the first and last valid cell of each row suffice
  for (int j = 0; j < dsm.height; ++j) {
    int first = -1, last = -1;
    for (int i = 0; i < dsm.width; ++i)
      if (std::isfinite(dsm.at(i, j))) last = i, first = first < 0 ? i : first;
    if (first >= 0) ends.insert(ends.end(), {cv::Point(first, j), cv::Point(last, j)});
  }
  cv::Mat mask(dsm.height, dsm.width, CV_8U, cv::Scalar(0));
  if (ends.empty()) return mask;
  std::vector<cv::Point> hull;
  cv::convexHull(ends, hull);
  cv::fillConvexPoly(mask, hull, cv::Scalar(255));
  return mask;
}

}  // namespace

size_t FillDsmHoles(Dsm* dsm, double max_distance_m) {
  if (!(max_distance_m > 0) || dsm->width == 0 || dsm->height == 0) return 0;
  const cv::Mat inside = HullMask(*dsm);
  size_t holes = 0;
  for (int j = 0; j < dsm->height; ++j)
    for (int i = 0; i < dsm->width; ++i)
      holes += !std::isfinite(dsm->at(i, j)) && inside.at<uint8_t>(j, i);
  if (holes == 0) return 0;

  // Band and validity mask as MEM rasters; GDAL interpolates where the mask is 0.
  const int w = dsm->width, h = dsm->height;
  DatasetPtr band_ds = MemDataset(w, h, GDT_Float32), mask_ds = MemDataset(w, h, GDT_Byte);
  std::vector<uint8_t> valid(size_t(w) * h);
  std::vector<float> z = dsm->z;
  for (size_t k = 0; k < z.size(); ++k) valid[k] = std::isfinite(z[k]) ? 1 : 0;
  GDALRasterBand* band = band_ds->GetRasterBand(1);
  GDALRasterBand* mask = mask_ds->GetRasterBand(1);
  SATMESH_CHECK(band->RasterIO(GF_Write, 0, 0, w, h, z.data(), w, h, GDT_Float32, 0, 0) == CE_None &&
                    mask->RasterIO(GF_Write, 0, 0, w, h, valid.data(), w, h, GDT_Byte, 0, 0) == CE_None,
                ErrorCode::kInternal, "GDAL: cannot write the DSM to a MEM raster");
  const double cell_m = std::abs(dsm->geo_transform[1]);
  const double max_cells = std::max(1.0, max_distance_m / cell_m);
  // GDAL's work rasters in memory: by default it writes them as GeoTIFFs into the current
  // directory (CPLGenerateTempFilename), which fails wherever that is not writable, as in
  // the image, a service, or a run from / (issue 17).
  CPLStringList fill_options;
  fill_options.SetNameValue("TEMP_FILE_DRIVER", "MEM");
  SATMESH_CHECK(GDALFillNodata(band, mask, max_cells, 0, 0, fill_options.List(), nullptr, nullptr) == CE_None,
                ErrorCode::kInternal, "GDALFillNodata failed: " + std::string(CPLGetLastErrorMsg()));
  // Cells GDAL found no valid cell for keep their NaN.
  SATMESH_CHECK(band->RasterIO(GF_Read, 0, 0, w, h, z.data(), w, h, GDT_Float32, 0, 0) == CE_None,
                ErrorCode::kInternal, "GDAL: cannot read the filled DSM back");
  size_t filled = 0;
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const size_t k = size_t(j) * w + i;
      if (std::isfinite(dsm->z[k]) || !inside.at<uint8_t>(j, i) || !std::isfinite(z[k]))
        continue;
      dsm->z[k] = z[k];
      ++filled;
    }
  }
  return filled;
}

}  // namespace satmesh
