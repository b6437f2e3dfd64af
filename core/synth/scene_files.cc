#include "core/synth/scene_files.h"

#include <cpl_string.h>
#include <gdal.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/common/error.h"
#include "core/common/gdal_init.h"

namespace satmesh::synth {
namespace {

GDALDatasetH CreateTif(const std::string& path, int w, int h, GDALDataType type) {
  EnsureGdalInitialized();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  char** opts = nullptr;
  opts = CSLSetNameValue(opts, "COMPRESS", "DEFLATE");
  opts = CSLSetNameValue(opts, "TILED", "YES");
  opts = CSLSetNameValue(opts, "PREDICTOR", "2");            // integer types only here
  opts = CSLSetNameValue(opts, "NUM_THREADS", "ALL_CPUS");   // compress tiles in parallel
  GDALDatasetH ds = GDALCreate(driver, path.c_str(), w, h, 1, type, opts);
  CSLDestroy(opts);
  SATMESH_CHECK(ds != nullptr, ErrorCode::kIo, "cannot create " + path);
  return ds;
}

std::string Num(double v) {
  std::ostringstream s;
  s << std::setprecision(15) << v;
  return s.str();
}

// Percentile of the finite values.
float Percentile(std::vector<float> v, double q) {
  v.erase(std::remove_if(v.begin(), v.end(), [](float x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return 0.f;
  const size_t k = std::min(v.size() - 1, size_t(q * (v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

cv::Mat ToTile(const std::vector<float>& px, int w, int h, float lo, float hi, int tile) {
  cv::Mat m(h, w, CV_8U);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const float v = px[size_t(j) * w + i];
      m.at<uint8_t>(j, i) = std::isfinite(v) ? uint8_t(std::clamp((v - lo) / (hi - lo), 0.f, 1.f) * 255) : 0;
    }
  const double s = double(tile) / std::max(w, h);
  cv::Mat small;
  cv::resize(m, small, cv::Size(std::max(1, int(w * s)), std::max(1, int(h * s))), 0, 0, cv::INTER_AREA);
  cv::Mat out(tile, tile, CV_8U, cv::Scalar(32));
  small.copyTo(out(cv::Rect(0, 0, small.cols, small.rows)));
  return out;
}

}  // namespace

void WriteImageWithRpc(const std::string& path, const ImageF& dn, const RpcModel& rpc,
                       const AcquisitionInfo& acquisition) {
  GDALDatasetH ds = CreateTif(path, dn.width, dn.height, GDT_UInt16);
  std::vector<uint16_t> px(dn.pixels.size());
  for (size_t k = 0; k < px.size(); ++k)
    px[k] = uint16_t(std::clamp(std::round(dn.pixels[k]), 0.f, 65535.f));
  CPLErr err = GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, dn.width, dn.height, px.data(),
                            dn.width, dn.height, GDT_UInt16, 0, 0);
  char** md = nullptr;
  for (const auto& [k, v] : rpc.ToKeyValues()) md = CSLSetNameValue(md, k.c_str(), v.c_str());
  if (err == CE_None) err = GDALSetMetadata(ds, md, "RPC");
  CSLDestroy(md);
  char** imd = nullptr;
  for (const auto& [k, v] : ImdMetadata(acquisition)) imd = CSLSetNameValue(imd, k.c_str(), v.c_str());
  if (err == CE_None && imd) err = GDALSetMetadata(ds, imd, "IMD");
  CSLDestroy(imd);
  GDALClose(ds);
  SATMESH_CHECK(err == CE_None, ErrorCode::kIo, "cannot write " + path);
}

void WriteMaskTif(const std::string& path, const Dsm& grid, const std::vector<uint8_t>& mask) {
  GDALDatasetH ds = CreateTif(path, grid.width, grid.height, GDT_Byte);
  double gt[6];
  std::copy(grid.geo_transform.begin(), grid.geo_transform.end(), gt);
  GDALSetGeoTransform(ds, gt);
  GDALSetProjection(ds, grid.crs_wkt.c_str());
  const CPLErr err = GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, grid.width, grid.height,
                                  const_cast<uint8_t*>(mask.data()), grid.width, grid.height,
                                  GDT_Byte, 0, 0);
  GDALClose(ds);
  SATMESH_CHECK(err == CE_None, ErrorCode::kIo, "cannot write " + path);
}

void WritePointsPly(const std::string& path, const std::vector<Eigen::Vector3d>& points,
                    const std::vector<Eigen::Vector3f>& normals) {
  std::ofstream f(path, std::ios::binary);
  SATMESH_CHECK(f.good(), ErrorCode::kIo, "cannot create " + path);
  f << "ply\nformat binary_little_endian 1.0\nelement vertex " << points.size()
    << "\nproperty double x\nproperty double y\nproperty double z\n"
       "property float nx\nproperty float ny\nproperty float nz\nend_header\n";
  for (size_t i = 0; i < points.size(); ++i) {
    f.write(reinterpret_cast<const char*>(points[i].data()), 3 * sizeof(double));
    f.write(reinterpret_cast<const char*>(normals[i].data()), 3 * sizeof(float));
  }
  SATMESH_CHECK(f.good(), ErrorCode::kIo, "cannot write " + path);
}

void WriteSceneJson(const std::string& path, const SynthOptions& o, const SynthResult& r) {
  std::ostringstream s;
  s << "{\n  \"preset\": \"" << o.preset << "\",\n  \"seed\": " << o.seed << ",\n  \"crs\": \""
    << o.crs << "\",\n  \"gsd_m\": " << Num(o.gsd_m) << ",\n  \"aoi\": {\"xmin\": " << Num(r.aoi_xmin)
    << ", \"ymin\": " << Num(r.aoi_ymin) << ", \"xmax\": " << Num(r.aoi_xmax)
    << ", \"ymax\": " << Num(r.aoi_ymax) << "},\n  \"height_range_m\": [" << Num(r.height_min_m)
    << ", " << Num(r.height_max_m) << "],\n  \"acquisition\": \"" << AcquisitionName(o.views.acquisition)
    << "\",\n  \"rpc_bias_sigma_px\": " << Num(o.rpc_bias_sigma_px) << ",\n  \"views\": [\n";
  for (size_t i = 0; i < r.views.size(); ++i) {
    const SynthView& v = r.views[i];
    s << "    {\"image\": \"" << v.image << "\", \"off_nadir_deg\": " << Num(v.off_nadir_deg)
      << ", \"azimuth_deg\": " << Num(v.azimuth_deg) << ", \"zenith_deg\": " << Num(v.zenith_deg)
      << ", \"gsd_m\": " << Num(v.gsd_m) << ", \"pass\": " << v.pass << ", \"track_heading_deg\": "
      << Num(v.track_heading_deg) << ", \"acquisition_time\": \"" << FormatIso8601Utc(v.acquisition_unix_s)
      << "\", \"acquisition_unix_s\": " << Num(v.acquisition_unix_s) << ", \"sun\": {\"azimuth_deg\": "
      << Num(v.sun.azimuth_deg) << ", \"elevation_deg\": " << Num(v.sun.elevation_deg) << "}, \"width\": " << v.width << ", \"height\": " << v.height
      << ", \"rpc_fit_max_px\": " << Num(v.rpc_fit_max_half_step_px)
      << ", \"ray_grid_error_px\": " << Num(v.ray_grid_error_px) << ", \"bias_col_row_px\": ["
      << Num(v.bias_col_row_px.x()) << ", " << Num(v.bias_col_row_px.y()) << "], \"gain\": "
      << Num(v.gain) << ", \"offset_dn\": " << Num(v.offset_dn) << "}"
      << (i + 1 < r.views.size() ? ",\n" : "\n");
  }
  s << "  ],\n  \"truth\": {\"mesh\": \"truth/mesh.ply\", \"dsm\": \"truth/dsm.tif\", "
       "\"roof_mask\": \"truth/roof_mask.tif\", \"facade_points\": \"truth/facade_points.ply\"},\n"
       "  \"initial\": {\"dsm\": \"initial/dsm.tif\", \"roof_nmad_m\": "
    << Num(r.initial_roof_nmad_m) << ", \"roof_p68_m\": " << Num(r.initial_roof_p68_m) << "}\n}\n";
  std::ofstream f(path);
  f << s.str();
  SATMESH_CHECK(f.good(), ErrorCode::kIo, "cannot write " + path);
}

void WriteJobJson(const std::string& path, const SynthOptions& o, const SynthResult& r) {
  std::ostringstream s;
  s << "{\n  \"images\": [\n";
  for (size_t i = 0; i < r.views.size(); ++i)
    s << "    {\"href\": \"" << r.views[i].image << "\"}" << (i + 1 < r.views.size() ? ",\n" : "\n");
  s << "  ],\n  \"initial\": {\"dsm\": \"initial/dsm.tif\"},\n  \"outputs\": {\"crs\": \"" << o.crs
    << "\"}";
  // The RPCs are exact unless a bias was injected: estimating one over the (degraded)
  // initial surface would only add its ~0.1 px noise (docs/benchmarks-history.md, Run 3).
  if (o.rpc_bias_sigma_px == 0) s << ",\n  \"options\": {\"estimate_bias\": false}";
  s << "\n}\n";
  std::ofstream f(path);
  f << s.str();
  SATMESH_CHECK(f.good(), ErrorCode::kIo, "cannot write " + path);
}

void WritePreview(const std::string& path, const std::vector<ImageF>& views,
                  const std::vector<std::string>& labels, const Dsm& truth, const Dsm& initial) {
  const int tile = 320, cols = 4;
  std::vector<std::pair<cv::Mat, std::string>> tiles;
  for (size_t i = 0; i < views.size(); ++i) {
    const float lo = Percentile(views[i].pixels, 0.005), hi = Percentile(views[i].pixels, 0.995);
    tiles.emplace_back(ToTile(views[i].pixels, views[i].width, views[i].height, lo, hi + 1, tile),
                       labels[i]);
  }
  const float zlo = Percentile(truth.z, 0.01), zhi = Percentile(truth.z, 0.99);
  tiles.emplace_back(ToTile(truth.z, truth.width, truth.height, zlo, zhi, tile), "truth DSM");
  tiles.emplace_back(ToTile(initial.z, initial.width, initial.height, zlo, zhi, tile), "initial DSM");
  std::vector<float> err(truth.z.size());
  for (size_t k = 0; k < err.size(); ++k) err[k] = std::abs(initial.z[k] - truth.z[k]);
  tiles.emplace_back(ToTile(err, truth.width, truth.height, 0.f, 3.f, tile), "|initial-truth| 0-3 m");
  const int rows = int(tiles.size() + cols - 1) / cols;
  cv::Mat sheet(rows * tile, cols * tile, CV_8U, cv::Scalar(0));
  for (size_t t = 0; t < tiles.size(); ++t) {
    cv::Mat roi = sheet(cv::Rect(int(t % cols) * tile, int(t / cols) * tile, tile, tile));
    tiles[t].first.copyTo(roi);
    cv::putText(roi, tiles[t].second, cv::Point(4, tile - 8), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                cv::Scalar(255), 1, cv::LINE_AA);
    cv::rectangle(roi, cv::Rect(0, 0, tile, tile), cv::Scalar(80), 1);
  }
  SATMESH_CHECK(cv::imwrite(path, sheet), ErrorCode::kIo, "cannot write " + path);
}

}  // namespace satmesh::synth
