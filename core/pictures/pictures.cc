#include "core/pictures/pictures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/common/error.h"

namespace satmesh {
namespace {

const cv::Scalar kBackground(255, 255, 255), kInk(40, 40, 40), kNoData(150, 150, 150);
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

void WritePng(const std::string& path, const cv::Mat& image) {
  bool ok = false;
  try {
    ok = cv::imwrite(path, image);
  } catch (const cv::Exception& e) {
    ThrowError(ErrorCode::kIo, "cannot write '" + path + "': " + e.what());
  }
  SATMESH_CHECK(ok, ErrorCode::kIo, "cannot write '" + path + "'");
}

void Text(cv::Mat& image, const std::string& text, cv::Point at, double scale = 0.5,
          cv::Scalar color = kInk, int thickness = 1) {
  cv::putText(image, text, at, kFont, scale, color, thickness, cv::LINE_AA);
}

int TextWidth(const std::string& text, double scale = 0.5) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, 1, &baseline).width;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Diverging blue - white - red for t in [-1, 1] (BGR).
cv::Vec3b Diverging(double t) {
  t = std::clamp(t, -1.0, 1.0);
  const cv::Vec3d white(245, 245, 245), blue(204, 102, 33), red(38, 38, 204);
  const cv::Vec3d c = t < 0 ? white + (-t) * (blue - white) : white + t * (red - white);
  return cv::Vec3b(uchar(c[0]), uchar(c[1]), uchar(c[2]));
}

// A "nice" step (1, 2, 5 x 10^k) for about `count` ticks over `span`.
double TickStep(double span, int count) {
  const double raw = span / std::max(1, count);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (raw <= m * power) return m * power;
  return 10 * power;
}

}  // namespace

std::string HillshadeOptions::Check() const {
  if (!(sun_azimuth_deg >= 0 && sun_azimuth_deg < 360)) return "sun_azimuth_deg: not in [0, 360)";
  if (!(sun_elevation_deg > 0 && sun_elevation_deg <= 90))
    return "sun_elevation_deg: not in (0, 90]";
  if (!(z_factor > 0)) return "z_factor: must be > 0";
  if (max_size_px < 16) return "max_size_px: must be >= 16";
  return "";
}

void WriteHillshadePng(const std::string& path, const Dsm& dsm, const HillshadeOptions& options) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "HillshadeOptions: " + problem);
  SATMESH_CHECK(dsm.width >= 3 && dsm.height >= 3, ErrorCode::kInvalidArgument,
                "hillshade of '" + path + "': the DSM has fewer than 3 x 3 cells");
  const double dx = std::abs(dsm.geo_transform[1]), dy = std::abs(dsm.geo_transform[5]);
  const double zenith = (90 - options.sun_elevation_deg) * std::numbers::pi / 180;
  // The sun's direction in the math convention (counter-clockwise from east).
  const double azimuth = (360 - options.sun_azimuth_deg + 90) * std::numbers::pi / 180;
  cv::Mat image(dsm.height, dsm.width, CV_8UC3, cv::Scalar(70, 40, 30));
  for (int j = 1; j + 1 < dsm.height; ++j) {
    for (int i = 1; i + 1 < dsm.width; ++i) {
      float z[3][3];
      bool valid = true;
      for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a)
          valid = valid && std::isfinite(z[b][a] = dsm.at(i + a - 1, j + b - 1));
      if (!valid) continue;
      // Horn's gradient, x east and y south (rows), as the aspect formula below takes it.
      const double dzdx =
          ((z[0][2] + 2 * z[1][2] + z[2][2]) - (z[0][0] + 2 * z[1][0] + z[2][0])) / (8 * dx);
      const double dzdy =
          ((z[2][0] + 2 * z[2][1] + z[2][2]) - (z[0][0] + 2 * z[0][1] + z[0][2])) / (8 * dy);
      const double slope = std::atan(options.z_factor * std::hypot(dzdx, dzdy));
      const double aspect = std::atan2(dzdy, -dzdx);
      const double shade = std::cos(zenith) * std::cos(slope) +
                           std::sin(zenith) * std::sin(slope) * std::cos(azimuth - aspect);
      const uchar grey = uchar(std::clamp(255.0 * shade, 0.0, 255.0));
      image.at<cv::Vec3b>(j, i) = cv::Vec3b(grey, grey, grey);
    }
  }
  // Reduced to max_size_px, or enlarged (by a whole factor) to at least 512 px.
  const int longer = std::max(dsm.width, dsm.height);
  const double scale =
      longer > options.max_size_px
          ? double(options.max_size_px) / longer
          : std::max(1.0, std::floor(std::min(512.0, double(options.max_size_px)) / longer));
  if (scale < 1) cv::resize(image, image, cv::Size(), scale, scale, cv::INTER_AREA);
  if (scale > 1) cv::resize(image, image, cv::Size(), scale, scale, cv::INTER_NEAREST);
  WritePng(path, image);
}

void WriteHeightErrorMapsPng(const std::string& path, const std::vector<TitledDsm>& surfaces,
                             const Dsm& truth, double range_m) {
  SATMESH_CHECK(range_m > 0, ErrorCode::kInvalidArgument, "height error map: range_m must be > 0");
  SATMESH_CHECK(!surfaces.empty() && truth.width > 0 && truth.height > 0,
                ErrorCode::kInvalidArgument, "height error map: no surface or an empty truth");
  for (const auto& s : surfaces)
    SATMESH_CHECK(s.dsm && s.dsm->width == truth.width && s.dsm->height == truth.height,
                  ErrorCode::kInvalidArgument,
                  "height error map: '" + s.title + "' is not on the truth's grid");
  // Each panel at most 640 px wide; title above, one legend below all.
  const double scale = std::min(4.0, 640.0 / std::max(truth.width, truth.height));
  const int pw = std::max(1, int(truth.width * scale)), ph = std::max(1, int(truth.height * scale));
  const int margin = 20, title_h = 34, legend_h = 70;
  cv::Mat image(title_h + ph + legend_h + margin, margin + int(surfaces.size()) * (pw + margin),
                CV_8UC3, kBackground);
  for (size_t k = 0; k < surfaces.size(); ++k) {
    cv::Mat panel(truth.height, truth.width, CV_8UC3);
    for (int j = 0; j < truth.height; ++j)
      for (int i = 0; i < truth.width; ++i) {
        const float a = surfaces[k].dsm->at(i, j), t = truth.at(i, j);
        panel.at<cv::Vec3b>(j, i) =
            std::isfinite(a) && std::isfinite(t)
                ? Diverging((a - t) / range_m)
                : cv::Vec3b(uchar(kNoData[0]), uchar(kNoData[1]), uchar(kNoData[2]));
      }
    cv::resize(panel, panel, cv::Size(pw, ph), 0, 0, cv::INTER_NEAREST);
    const int x0 = margin + int(k) * (pw + margin);
    panel.copyTo(image(cv::Rect(x0, title_h, pw, ph)));
    Text(image, surfaces[k].title, cv::Point(x0, title_h - 10), 0.55);
  }
  // Legend: the colour bar with ticks at -range, -range/2, 0, range/2, range.
  const int bar_w = std::min(image.cols - 2 * margin, 480), bar_x = (image.cols - bar_w) / 2;
  const int bar_y = title_h + ph + 14;
  for (int x = 0; x < bar_w; ++x)
    cv::line(image, cv::Point(bar_x + x, bar_y), cv::Point(bar_x + x, bar_y + 14),
             cv::Scalar(Diverging(2.0 * x / (bar_w - 1) - 1)), 1);
  for (int t = 0; t <= 4; ++t) {
    const int x = bar_x + t * (bar_w - 1) / 4;
    const std::string label = Format("%+.2g", range_m * (t - 2) / 2.0);
    cv::line(image, cv::Point(x, bar_y + 14), cv::Point(x, bar_y + 19), kInk, 1);
    Text(image, t == 2 ? "0" : label,
         cv::Point(x - TextWidth(t == 2 ? "0" : label, 0.45) / 2, bar_y + 34), 0.45);
  }
  const std::string caption = "height - truth (m); grey: no data";
  Text(image, caption, cv::Point(bar_x + bar_w / 2 - TextWidth(caption, 0.45) / 2, bar_y + 52),
       0.45);
  WritePng(path, image);
}

void WritePointMapsPng(const std::string& path, const std::vector<PointPanel>& panels,
                       const std::array<double, 4>& extent, double max_value,
                       const std::string& caption) {
  const double ex = extent[2] - extent[0], ey = extent[3] - extent[1];
  SATMESH_CHECK(ex > 0 && ey > 0 && max_value > 0 && !panels.empty(), ErrorCode::kInvalidArgument,
                "point map '" + path + "': empty extent, no panel or max_value <= 0");
  cv::Mat lut(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) lut.at<uchar>(0, i) = uchar(i);
  cv::applyColorMap(lut, lut, cv::COLORMAP_VIRIDIS);  // 1 x 256 BGR
  const auto color = [&](double v) {
    const cv::Vec3b c = lut.at<cv::Vec3b>(0, int(std::clamp(v / max_value, 0.0, 1.0) * 255));
    return cv::Scalar(c[0], c[1], c[2]);
  };
  const double scale = 640.0 / std::max(ex, ey);
  const int pw = int(ex * scale), ph = int(ey * scale), margin = 20, title_h = 34, legend_h = 70;
  cv::Mat image(title_h + ph + legend_h + margin, margin + int(panels.size()) * (pw + margin),
                CV_8UC3, kBackground);
  for (size_t k = 0; k < panels.size(); ++k) {
    const PointPanel& p = panels[k];
    SATMESH_CHECK(p.xy.size() == p.values.size(), ErrorCode::kInvalidArgument,
                  "point map '" + p.title + "': " + std::to_string(p.values.size()) +
                      " values for " + std::to_string(p.xy.size()) + " points");
    const int x0 = margin + int(k) * (pw + margin);
    cv::rectangle(image, cv::Rect(x0, title_h, pw, ph), cv::Scalar(235, 235, 235), cv::FILLED);
    // Points falling on the same 3 x 3 px cell (a wall seen from above) show their mean.
    constexpr int kCell = 3;
    const int cw = pw / kCell + 1, ch = ph / kCell + 1;
    std::vector<double> sum(size_t(cw) * ch, 0.0);
    std::vector<int> count(sum.size(), 0);
    for (size_t i = 0; i < p.xy.size(); ++i) {
      if (!std::isfinite(p.values[i])) continue;
      const int cx = int((p.xy[i].x() - extent[0]) * scale) / kCell,
                cy = int((extent[3] - p.xy[i].y()) * scale) / kCell;
      if (cx < 0 || cy < 0 || cx >= cw || cy >= ch) continue;
      sum[size_t(cy) * cw + cx] += std::min<double>(p.values[i], max_value);
      ++count[size_t(cy) * cw + cx];
    }
    for (int cy = 0; cy < ch; ++cy)
      for (int cx = 0; cx < cw; ++cx) {
        const size_t c = size_t(cy) * cw + cx;
        if (count[c] == 0) continue;
        const cv::Rect cell(x0 + cx * kCell, title_h + cy * kCell, kCell, kCell);
        cv::rectangle(image, cell & cv::Rect(x0, title_h, pw, ph), color(sum[c] / count[c]),
                      cv::FILLED);
      }
    Text(image, p.title, cv::Point(x0, title_h - 10), 0.55);
  }
  const int bar_w = std::min(image.cols - 2 * margin, 480), bar_x = (image.cols - bar_w) / 2;
  const int bar_y = title_h + ph + 14;
  for (int x = 0; x < bar_w; ++x)
    cv::line(image, cv::Point(bar_x + x, bar_y), cv::Point(bar_x + x, bar_y + 14),
             color(max_value * x / (bar_w - 1)), 1);
  for (int t = 0; t <= 4; ++t) {
    const int x = bar_x + t * (bar_w - 1) / 4;
    const std::string label = Format("%.2g", max_value * t / 4.0) + (t == 4 ? "+" : "");
    cv::line(image, cv::Point(x, bar_y + 14), cv::Point(x, bar_y + 19), kInk, 1);
    Text(image, label, cv::Point(x - TextWidth(label, 0.45) / 2, bar_y + 34), 0.45);
  }
  Text(image, caption, cv::Point(bar_x + bar_w / 2 - TextWidth(caption, 0.45) / 2, bar_y + 52),
       0.45);
  WritePng(path, image);
}

void WriteLinePlotPng(const std::string& path, const std::vector<PlotSeries>& series,
                      const std::string& title, const std::string& x_label,
                      const std::string& y_label) {
  double y0 = INFINITY, y1 = -INFINITY;
  size_t n = 0;
  for (const auto& s : series) {
    n = std::max(n, s.y.size());
    for (double v : s.y)
      if (std::isfinite(v)) y0 = std::min(y0, v), y1 = std::max(y1, v);
  }
  SATMESH_CHECK(std::isfinite(y0), ErrorCode::kInvalidArgument,
                "plot '" + title + "': no finite value");
  if (y1 - y0 < 1e-6) y0 -= 0.01, y1 += 0.01;
  const int w = 900, h = 560, left = 80, right = 30, top = 50, bottom = 60;
  // Room above the data for the legend (top right), and a little below.
  const double legend_px = 22.0 * double(series.size()) + 16, plot_px = h - top - bottom;
  const double span = y1 - y0;
  y0 -= 0.05 * span;
  y1 += span * (legend_px / (plot_px - legend_px) + 0.05);
  cv::Mat image(h, w, CV_8UC3, kBackground);
  const double x_max = std::max<double>(1, double(n) - 1);
  const auto px = [&](double x) { return left + int(std::lround(x / x_max * (w - left - right))); };
  const auto py = [&](double y) {
    return top + int(std::lround((y1 - y) / (y1 - y0) * (h - top - bottom)));
  };
  // Grid and ticks.
  const double ystep = TickStep(y1 - y0, 6);
  for (double y = std::ceil(y0 / ystep) * ystep; y <= y1; y += ystep) {
    cv::line(image, cv::Point(left, py(y)), cv::Point(w - right, py(y)), cv::Scalar(225, 225, 225),
             1);
    const std::string label = Format(ystep < 0.01 ? "%.3f" : "%.2f", y);
    Text(image, label, cv::Point(left - 8 - TextWidth(label, 0.45), py(y) + 5), 0.45);
  }
  const double xstep = std::max(1.0, TickStep(x_max, 10));
  for (double x = 0; x <= x_max + 1e-9; x += xstep) {
    cv::line(image, cv::Point(px(x), h - bottom), cv::Point(px(x), h - bottom + 5), kInk, 1);
    const std::string label = Format("%.0f", x);
    Text(image, label, cv::Point(px(x) - TextWidth(label, 0.45) / 2, h - bottom + 22), 0.45);
  }
  cv::rectangle(image, cv::Point(left, top), cv::Point(w - right, h - bottom), kInk, 1);
  Text(image, title, cv::Point(left, top - 18), 0.65, kInk, 2);
  Text(image, x_label, cv::Point(left + (w - left - right) / 2 - TextWidth(x_label) / 2, h - 14));
  cv::Mat ylab(24, TextWidth(y_label) + 8, CV_8UC3, kBackground);
  Text(ylab, y_label, cv::Point(4, 17));
  cv::rotate(ylab, ylab, cv::ROTATE_90_COUNTERCLOCKWISE);
  if (ylab.rows <= h)
    ylab.copyTo(image(cv::Rect(6, top + (h - top - bottom - ylab.rows) / 2, ylab.cols, ylab.rows)));
  // Series, and the legend (top right).
  const cv::Scalar palette[] = {{180, 119, 31}, {14, 127, 255},  {44, 160, 44},
                                {40, 39, 214},  {189, 103, 148}, {75, 86, 140}};
  int legend_y = top + 22;
  for (size_t k = 0; k < series.size(); ++k) {
    const cv::Scalar color = palette[k % 6];
    std::vector<cv::Point> line;
    for (size_t i = 0; i < series[k].y.size(); ++i)
      if (std::isfinite(series[k].y[i])) line.emplace_back(px(double(i)), py(series[k].y[i]));
    if (line.size() > 1) cv::polylines(image, line, /*isClosed=*/false, color, 2, cv::LINE_AA);
    for (const auto& p : line) cv::circle(image, p, 3, color, cv::FILLED, cv::LINE_AA);
    const int lx = w - right - 16 - TextWidth(series[k].name) - 34;
    cv::line(image, cv::Point(lx, legend_y - 5), cv::Point(lx + 26, legend_y - 5), color, 2,
             cv::LINE_AA);
    Text(image, series[k].name, cv::Point(lx + 32, legend_y));
    legend_y += 22;
  }
  WritePng(path, image);
}

}  // namespace satmesh
