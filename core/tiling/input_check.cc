#include "core/tiling/input_check.h"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/geo/crs.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"

namespace satmesh {
namespace {

struct DatasetCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using DatasetPtr = std::unique_ptr<GDALDataset, DatasetCloser>;

std::string Quoted(const std::string& path) { return "'" + path + "'"; }

std::string GdalMessage() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg && *msg) ? std::string(" (GDAL: ") + msg + ")" : std::string();
}

std::string Lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsFeet(const std::string& unit) {
  const std::string u = Lower(unit);
  return u == "ft" || u == "us-ft" || u == "ftus" || u.find("foot") != std::string::npos ||
         u.find("feet") != std::string::npos;
}

std::string Number(double v, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  return text;
}

// --- initial.dsm ---------------------------------------------------------------------

// Heights must be metres: the band's unit and any vertical CRS's unit.
void CheckDsmUnits(const std::string& path, GDALDataset& ds) {
  const std::string field = "initial.dsm: " + Quoted(path);
  const std::string band_unit = ds.GetRasterBand(1)->GetUnitType();
  SATMESH_CHECK(!IsFeet(band_unit), ErrorCode::kInvalidInput,
                field + ": heights are in feet (band unit '" + band_unit +
                    "'); satmesh needs ellipsoidal heights in metres (x 0.3048 for the "
                    "international foot, x 1200/3937 for the US survey foot)");
  const OGRSpatialReference* srs = ds.GetSpatialRef();
  if (srs == nullptr) return;
  const char* unit_name = nullptr;
  const double horizontal = srs->GetLinearUnits(&unit_name);
  SATMESH_CHECK(!srs->IsProjected() || std::abs(horizontal - 1.0) < 1e-9, ErrorCode::kInvalidInput,
                field + ": the CRS's x/y are in " + (unit_name ? unit_name : "?") + " (" +
                    Number(horizontal, 6) + " m); satmesh needs a projected CRS in metres");
  if (srs->IsCompound() || srs->IsVertical()) {
    const double vertical = srs->GetTargetLinearUnits("VERT_CS", &unit_name);
    SATMESH_CHECK(std::abs(vertical - 1.0) < 1e-9, ErrorCode::kInvalidInput,
                  field + ": heights are in " + std::string(unit_name ? unit_name : "?") + " (" +
                      Number(vertical, 6) + " m, the vertical CRS's unit); satmesh needs metres");
  }
}

// The AOI's range of valid heights, read in row blocks until a block holds one (the whole
// AOI only when it is all nodata). Throws naming the nodata value when there is none.
std::pair<float, float> AoiHeightRange(const std::string& path, GDALDataset& ds, const PixelWindow& aoi) {
  GDALRasterBand* band = ds.GetRasterBand(1);
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  const int rows_per_block = std::max(1, int(4'000'000 / std::max(1, aoi.width)));
  std::vector<float> buffer;
  for (int row = aoi.row0; row < aoi.row0 + aoi.height; row += rows_per_block) {
    const int rows = std::min(rows_per_block, aoi.row0 + aoi.height - row);
    buffer.resize(size_t(aoi.width) * rows);
    CPLErrorReset();
    SATMESH_CHECK(band->RasterIO(GF_Read, aoi.col0, row, aoi.width, rows, buffer.data(), aoi.width,
                                 rows, GDT_Float32, 0, 0, nullptr) == CE_None,
                  ErrorCode::kInvalidInput,
                  "initial.dsm: " + Quoted(path) + ": rows " + std::to_string(row) + ".." +
                      std::to_string(row + rows - 1) + " cannot be read (truncated or corrupt?)" +
                      GdalMessage());
    float lo = INFINITY, hi = -INFINITY;
    for (float z : buffer)
      if (std::isfinite(z) && !(has_nodata && z == float(nodata))) lo = std::min(lo, z), hi = std::max(hi, z);
    if (lo <= hi) return {lo, hi};
  }
  ThrowError(ErrorCode::kInvalidInput,
             "initial.dsm: " + Quoted(path) + ": all " + std::to_string(int64_t(aoi.width) * aoi.height) +
                 " cells of the AOI are nodata" +
                 (has_nodata ? " (nodata value " + Number(nodata, 3) + ")" : std::string(" (NaN)")) +
                 "; there is no surface to refine");
}

// --- images[i] -----------------------------------------------------------------------

struct CheckedImage {
  std::string field, path, real_path;
  RasterInfo info;
  RpcModel rpc;
};

// Opens the image and reads its first and last pixel: a truncated file fails here, not in
// the tile that reads its last rows.
RasterInfo CheckRaster(const std::string& field, const std::string& path) {
  RasterInfo info;
  try {
    info = ReadRasterInfo(path);
  } catch (const Error& e) {
    ThrowError(e.code() == ErrorCode::kNotFound ? ErrorCode::kNotFound : ErrorCode::kInvalidInput,
               field + ": " + Quoted(path) + " is not a readable raster: " + e.what());
  }
  SATMESH_CHECK(info.bands >= 1, ErrorCode::kInvalidInput, field + ": " + Quoted(path) + " has no band");
  SATMESH_CHECK(info.width >= kMinImageSidePx && info.height >= kMinImageSidePx, ErrorCode::kInvalidInput,
                field + ": " + Quoted(path) + " is " + std::to_string(info.width) + "x" +
                    std::to_string(info.height) + " pixels; an image needs at least " +
                    std::to_string(kMinImageSidePx) + "x" + std::to_string(kMinImageSidePx));
  for (const PixelWindow& corner : {PixelWindow{0, 0, 1, 1}, PixelWindow{info.width - 1, info.height - 1, 1, 1}}) {
    try {
      CPLErrorReset();
      ReadImageWindow(path, 1, corner);
    } catch (const Error& e) {
      ThrowError(ErrorCode::kInvalidInput, field + ": " + Quoted(path) + ": pixel (" +
                                               std::to_string(corner.col0) + ", " + std::to_string(corner.row0) +
                                               ") cannot be read (truncated or corrupt file?): " + e.what());
    }
  }
  return info;
}

std::string RealPath(const std::string& path) {
  if (path.rfind("/vsi", 0) == 0) return path;
  std::error_code ec;
  const auto real = std::filesystem::weakly_canonical(path, ec);
  return ec ? path : real.string();
}

bool SameCoefficients(const RpcCoefficients& a, const RpcCoefficients& b) {
  return a.line_off == b.line_off && a.samp_off == b.samp_off && a.lat_off == b.lat_off &&
         a.long_off == b.long_off && a.height_off == b.height_off && a.line_scale == b.line_scale &&
         a.samp_scale == b.samp_scale && a.lat_scale == b.lat_scale && a.long_scale == b.long_scale &&
         a.height_scale == b.height_scale && a.line_num == b.line_num && a.line_den == b.line_den &&
         a.samp_num == b.samp_num && a.samp_den == b.samp_den;
}

// The AOI's corners and centre at its lowest and highest height, geodetic (lon, lat, h).
std::vector<Eigen::Vector3d> AoiGeo(const JobPlan& plan, std::pair<float, float> heights) {
  const Box2d box = plan.dsm.BoxOf(plan.aoi_cells);
  const CrsTransform geo_from_dsm(plan.dsm.crs_wkt, kWgs84Geographic3D);
  std::vector<Eigen::Vector3d> points;
  for (double fx : {0.0, 0.5, 1.0})
    for (double fy : {0.0, 0.5, 1.0})
      for (double h : {double(heights.first), double(heights.second)})
        points.push_back(geo_from_dsm.Apply(
            Eigen::Vector3d(box.xmin + fx * box.width(), box.ymin + fy * box.height(), h)));
  return points;
}

// An image whose RPC's ground domain (offset +- 1.5 scales) misses the AOI is of another
// place; one whose RPC projects the AOI off its pixels has RPCs that do not belong to it.
void CheckImageSeesAoi(const CheckedImage& image, const std::vector<Eigen::Vector3d>& aoi_geo) {
  const RpcCoefficients& c = image.rpc.coefficients();
  double lon0 = 1e300, lon1 = -1e300, lat0 = 1e300, lat1 = -1e300;
  for (const auto& p : aoi_geo)
    lon0 = std::min(lon0, p.x()), lon1 = std::max(lon1, p.x()), lat0 = std::min(lat0, p.y()), lat1 = std::max(lat1, p.y());
  constexpr double kSlack = 1.5;
  const double dlat = kSlack * std::abs(c.lat_scale), dlon = kSlack * std::abs(c.long_scale);
  if (lat1 < c.lat_off - dlat || lat0 > c.lat_off + dlat || lon1 < c.long_off - dlon || lon0 > c.long_off + dlon) {
    const double lat_c = 0.5 * (lat0 + lat1), lon_c = 0.5 * (lon0 + lon1);
    const double km = 6371.0 * std::hypot((lat_c - c.lat_off) * M_PI / 180,
                                          (lon_c - c.long_off) * M_PI / 180 * std::cos(lat_c * M_PI / 180));
    ThrowError(ErrorCode::kInvalidInput,
               image.field + ": " + Quoted(image.path) + " is an image of another place: its RPC covers lat " +
                   Number(c.lat_off, 4) + " +- " + Number(std::abs(c.lat_scale), 4) + ", lon " +
                   Number(c.long_off, 4) + " +- " + Number(std::abs(c.long_scale), 4) +
                   "; the AOI is at lat " + Number(lat_c, 4) + ", lon " + Number(lon_c, 4) + " (" +
                   Number(km, 1) + " km away)");
  }
  double cmin = 1e300, cmax = -1e300, rmin = 1e300, rmax = -1e300;
  for (const auto& p : aoi_geo) {
    const Eigen::Vector2d px = image.rpc.PixelFromGeo(p);
    SATMESH_CHECK(px.allFinite(), ErrorCode::kInvalidInput,
                  image.field + ": " + Quoted(image.path) + ": its RPC does not project the AOI (a zero denominator)");
    cmin = std::min(cmin, px.x()), cmax = std::max(cmax, px.x()), rmin = std::min(rmin, px.y()), rmax = std::max(rmax, px.y());
  }
  SATMESH_CHECK(cmax > 0 && rmax > 0 && cmin < image.info.width && rmin < image.info.height,
                ErrorCode::kInvalidInput,
                image.field + ": " + Quoted(image.path) + ": its RPC puts the AOI outside the image: columns " +
                    Number(cmin, 0) + ".." + Number(cmax, 0) + ", rows " + Number(rmin, 0) + ".." +
                    Number(rmax, 0) + " of a " + std::to_string(image.info.width) + "x" +
                    std::to_string(image.info.height) + " image (RPC offsets wrong, or the RPC of another image?)");
}

CheckedImage CheckImage(const JobSpec& spec, size_t i, const std::vector<CheckedImage>& earlier) {
  CheckedImage image;
  image.field = "images[" + std::to_string(i) + "].href";
  image.path = spec.images[i].path;
  image.real_path = RealPath(image.path);
  for (const CheckedImage& e : earlier)
    SATMESH_CHECK(e.real_path != image.real_path, ErrorCode::kInvalidInput,
                  image.field + ": " + Quoted(image.path) + " is the same file as " + e.field +
                      " (each image may appear once)");
  image.info = CheckRaster(image.field, image.path);
  try {
    image.rpc = ReadRpc(image.path).WithBias(spec.images[i].bias_col_row_px);
  } catch (const Error& e) {
    ThrowError(e.code(), image.field + ": " + e.what());
  }
  for (const CheckedImage& e : earlier)
    SATMESH_CHECK(!(SameCoefficients(e.rpc.coefficients(), image.rpc.coefficients()) &&
                    e.info.width == image.info.width && e.info.height == image.info.height),
                  ErrorCode::kInvalidInput,
                  image.field + ": " + Quoted(image.path) + " has the same RPC and size as " + e.field + " " +
                      Quoted(e.path) + ": the same image twice (each image may appear once)");
  return image;
}

}  // namespace

void CheckJobInputs(const JobSpec& spec, const JobPlan& plan) {
  EnsureGdalInitialized();
  CPLErrorReset();
  std::pair<float, float> heights{float(plan.mesh_zmin), float(plan.mesh_zmax)};  // mesh jobs
  if (!spec.initial_dsm.empty()) {
    DatasetPtr dsm(GDALDataset::Open(spec.initial_dsm.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    SATMESH_CHECK(dsm != nullptr && dsm->GetRasterCount() >= 1, ErrorCode::kInvalidInput,
                  "initial.dsm: " + Quoted(spec.initial_dsm) + " is not a readable raster" + GdalMessage());
    CheckDsmUnits(spec.initial_dsm, *dsm);
    const std::pair<float, float> dsm_heights = AoiHeightRange(spec.initial_dsm, *dsm, plan.aoi_cells);
    heights = std::isfinite(heights.first)
                  ? std::pair<float, float>{std::min(heights.first, dsm_heights.first),
                                            std::max(heights.second, dsm_heights.second)}
                  : dsm_heights;
  }
  SATMESH_CHECK(std::isfinite(heights.first) && std::isfinite(heights.second), ErrorCode::kInvalidArgument,
                "the job has neither initial.dsm nor initial.mesh");
  const std::vector<Eigen::Vector3d> aoi_geo = AoiGeo(plan, heights);
  std::vector<CheckedImage> images;
  for (size_t i = 0; i < spec.images.size(); ++i) {
    images.push_back(CheckImage(spec, i, images));
    CheckImageSeesAoi(images.back(), aoi_geo);
  }
}

}  // namespace satmesh
