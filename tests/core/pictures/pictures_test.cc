#include "core/pictures/pictures.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/common/error.h"
#include "tests/scratch_dir.h"

namespace satmesh {
namespace {

namespace fs = std::filesystem;

std::string TempPath(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("satmesh_pictures_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  testing::RemoveAtExit(dir);
  return (dir / name).string();
}

// n x n cells of 1 m, z = f(x, y) with x east and y north (row 0 is the north edge).
template <typename F>
Dsm MakeDsm(int n, F f) {
  Dsm d;
  d.width = d.height = n;
  d.geo_transform = {0, 1, 0, double(n), 0, -1};
  d.z.resize(size_t(n) * n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) d.at(i, j) = float(f(i + 0.5, n - j - 0.5));
  return d;
}

double MeanGrey(const cv::Mat& image) { return cv::mean(image)[0]; }

TEST(HillshadeOptions, DefaultsAreValidAndFieldsNamed) {
  EXPECT_EQ(HillshadeOptions{}.Check(), "");
  HillshadeOptions o;
  o.sun_elevation_deg = 0;
  EXPECT_NE(o.Check().find("sun_elevation_deg"), std::string::npos);
  o = {};
  o.max_size_px = 4;
  EXPECT_NE(o.Check().find("max_size_px"), std::string::npos);
}

TEST(WriteHillshadePng, SlopesFacingTheSunAreBrighter) {
  // Sun from the north-west (default): a slope rising to the south-east faces it.
  const std::string toward = TempPath("toward.png"), away = TempPath("away.png"),
                    flat = TempPath("flat.png");
  WriteHillshadePng(toward, MakeDsm(32, [](double x, double y) { return 0.5 * (x - y); }));
  WriteHillshadePng(away, MakeDsm(32, [](double x, double y) { return 0.5 * (y - x); }));
  WriteHillshadePng(flat, MakeDsm(32, [](double, double) { return 10.0; }));
  const cv::Mat a = cv::imread(toward, cv::IMREAD_GRAYSCALE),
                b = cv::imread(away, cv::IMREAD_GRAYSCALE),
                c = cv::imread(flat, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a.cols, 512);                  // 32 cells enlarged by 16 to at least 512 px
  const cv::Rect inner(32, 32, 448, 448);  // away from the border cells
  // Flat at 45 deg elevation: 255 cos(45) = 180.
  EXPECT_NEAR(MeanGrey(c(inner)), 180.3, 1.0);
  // Slope atan(0.5 sqrt 2) = 35.3 deg, facing the sun: cos(45 - 35.3) = 0.986 -> 251;
  // facing away: cos(45 + 35.3) = 0.169 -> 43.
  EXPECT_NEAR(MeanGrey(a(inner)), 251.4, 1.5);
  EXPECT_NEAR(MeanGrey(b(inner)), 43.0, 1.5);
}

TEST(WriteHeightErrorMapsPng, OneScaleForEverySurface) {
  const Dsm truth = MakeDsm(20, [](double, double) { return 5.0; });
  const Dsm above = MakeDsm(20, [](double, double) { return 7.0; });  // +2 m: full red
  const Dsm exact = MakeDsm(20, [](double, double) { return 5.0; });  // 0: white
  Dsm holes = exact;
  holes.at(10, 10) = NAN;
  const std::string path = TempPath("errors.png");
  WriteHeightErrorMapsPng(path, {{"above", &above}, {"exact", &exact}}, truth, /*range_m=*/2.0);
  const cv::Mat image = cv::imread(path);
  ASSERT_FALSE(image.empty());
  // Panels: 20 cells at 4 px (scale capped at 4), from x = 20 and x = 120, y = 34.
  const cv::Vec3b red = image.at<cv::Vec3b>(34 + 40, 20 + 40),
                  white = image.at<cv::Vec3b>(34 + 40, 120 + 40);
  EXPECT_EQ(red, cv::Vec3b(38, 38, 204));
  EXPECT_EQ(white, cv::Vec3b(245, 245, 245));
  EXPECT_THROW(WriteHeightErrorMapsPng(path, {{"x", &above}},
                                       MakeDsm(10, [](double, double) { return 0.0; }), 2.0),
               Error);
  EXPECT_THROW(WriteHeightErrorMapsPng(path, {{"x", &above}}, truth, 0.0), Error);
}

TEST(WriteLinePlotPng, WritesAPlotAndRefusesNoData) {
  const std::string path = TempPath("plot.png");
  WriteLinePlotPng(path, {{"level 1", {0.5, 0.6, 0.65}}, {"level 0", {0.4, 0.45}}}, "zncc",
                   "iteration", "ZNCC");
  const cv::Mat image = cv::imread(path);
  EXPECT_EQ(image.cols, 900);
  EXPECT_EQ(image.rows, 560);
  EXPECT_THROW(WriteLinePlotPng(path, {{"empty", {}}, {"nan", {NAN}}}, "t", "x", "y"), Error);
}

}  // namespace
}  // namespace satmesh
