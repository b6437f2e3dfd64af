#pragma once
// Windowed raster reads and writes through GDAL.
#include <string>

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
// Reads one band (1-based) of a window into floats; the part of the window outside the
// raster is filled with `fill`. Throws Error naming file, band and window on failure.
ImageF ReadImageWindow(const std::string& path, int band, const PixelWindow& window,
                       float fill = 0.f);
// Reads the whole band.
ImageF ReadImage(const std::string& path, int band = 1);

// Writes an 8-bit PNG of the image, mapped linearly from [lo, hi] (for previews).
void WritePng(const std::string& path, const ImageF& image, float lo, float hi);

}  // namespace satmesh
