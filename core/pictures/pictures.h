#pragma once
// Pictures of results as PNG (OpenCV): a DSM's hillshade, maps of height errors against a
// truth, line plots (ZNCC per iteration). For people to look at; nothing reads them back.
#include <string>
#include <vector>

#include "core/dsm/dsm.h"

namespace satmesh {

struct HillshadeOptions {
  double sun_azimuth_deg = 315;   // direction of the sun, clockwise from north, [0, 360)
  double sun_elevation_deg = 45;  // above the horizon, (0, 90]
  double z_factor = 1;            // vertical exaggeration, > 0
  int max_size_px = 1600;         // longer side of the picture (a larger DSM is reduced), >= 16
  std::string Check() const;      // "" or what is wrong (field named)
};

// Grey hillshade of a DSM (Horn's gradient over 3 x 3 cells, the cells' size from the
// geotransform); cells without data dark blue. Throws Error{kInvalidArgument} for bad
// options or an empty DSM, Error{kIo} when the file cannot be written.
void WriteHillshadePng(const std::string& path, const Dsm& dsm, const HillshadeOptions& options = {});

// A surface on the truth's grid, with the title its panel carries.
struct TitledDsm {
  std::string title;
  const Dsm* dsm = nullptr;
};

// One panel per surface, side by side: surface - truth (m) on one diverging colour scale
// clipped at +-range_m (blue: below the truth, white: on it, red: above), cells where
// either has no data grey; one legend below. Throws Error{kInvalidArgument} when a surface
// is not on the truth's grid or range_m <= 0, Error{kIo} when the file cannot be written.
void WriteHeightErrorMapsPng(const std::string& path, const std::vector<TitledDsm>& surfaces,
                             const Dsm& truth, double range_m);

struct PlotSeries {
  std::string name;        // legend entry
  std::vector<double> y;   // value at x = 0, 1, ...
};

// Line plot of each series against its index, with axes, ticks, labels and a legend.
// Throws Error{kInvalidArgument} when no series has a finite value, Error{kIo} when the
// file cannot be written.
void WriteLinePlotPng(const std::string& path, const std::vector<PlotSeries>& series,
                      const std::string& title, const std::string& x_label, const std::string& y_label);

}  // namespace satmesh
