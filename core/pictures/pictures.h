#pragma once
// Pictures of results as PNG (OpenCV): a DSM's hillshade, maps of height errors against a
// truth, line plots (ZNCC per iteration). For people to look at; nothing reads them back.
#include <Eigen/Core>
#include <array>
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
void WriteHillshadePng(const std::string& path, const Dsm& dsm,
                       const HillshadeOptions& options = {});

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

// Values at points seen from above (e.g. facade samples' distance to a surface).
struct PointPanel {
  std::string title;
  std::vector<Eigen::Vector2d> xy;  // x east, y north, in the extent's frame
  std::vector<float> values;        // one per point; NaN not drawn
};

// One panel per point set, side by side over the same extent (xmin, ymin, xmax, ymax),
// each point a dot coloured by value on one scale [0, max_value] (viridis; larger values
// drawn on top), one legend below with `caption`. Throws Error{kInvalidArgument} for an
// empty extent, max_value <= 0 or values not matching the points, Error{kIo} when the
// file cannot be written.
void WritePointMapsPng(const std::string& path, const std::vector<PointPanel>& panels,
                       const std::array<double, 4>& extent, double max_value,
                       const std::string& caption);

struct PlotSeries {
  std::string name;       // legend entry
  std::vector<double> y;  // value at x = 0, 1, ...
};

// Line plot of each series against its index, with axes, ticks, labels and a legend.
// Throws Error{kInvalidArgument} when no series has a finite value, Error{kIo} when the
// file cannot be written.
void WriteLinePlotPng(const std::string& path, const std::vector<PlotSeries>& series,
                      const std::string& title, const std::string& x_label,
                      const std::string& y_label);

}  // namespace satmesh
