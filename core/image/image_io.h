#pragma once
// Windowed raster reads and writes through GDAL.
#include <string>

#include "core/image/acquisition_info.h"
#include "core/image/image.h"

namespace satmesh {

struct RasterInfo {
  int width = 0, height = 0, bands = 0;
  std::string data_type;  // GDAL name: "UInt16", "Float32", ...
};

struct PixelWindow {
  int col0 = 0, row0 = 0, width = 0, height = 0;  // in full-resolution pixels
};

// Throws Error{kNotFound}/{kIo} naming the file.
RasterInfo ReadRasterInfo(const std::string& path);
// The short name of the GDAL driver that would open `path` ("GTiff", "VRT", ...), found
// from the file's first bytes without opening it; "" when no driver recognises it.
std::string RasterDriverName(const std::string& path);
// Reads one band (1-based) of a window into floats; the part of the window outside the
// raster is filled with `fill`. Throws Error naming file, band and window on failure.
ImageF ReadImageWindow(const std::string& path, int band, const PixelWindow& window,
                       float fill = 0.f);
// Reads the whole band.
ImageF ReadImage(const std::string& path, int band = 1);

// Acquisition metadata of an image file from its "IMD" metadata domain (as GDAL exposes a
// WorldView .IMD/.XML or Pléiades DIM beside the image, or as stored in the file; see
// acquisition_info.h for the keys), the default domain's items of the same names as a
// fallback, and "IMAGERY" ACQUISITIONDATETIME for the time. Absent keys stay unset.
// Throws Error{kNotFound}/{kIo} naming the file.
AcquisitionInfo ReadAcquisitionInfo(const std::string& path);

// Writes an 8-bit PNG of the image, mapped linearly from [lo, hi] (for previews).
void WritePng(const std::string& path, const ImageF& image, float lo, float hi);

}  // namespace satmesh
