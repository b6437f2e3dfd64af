#include "core/dsm/dsm.h"

#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include <numbers>

#include "core/common/error.h"
#include "core/common/gdal_init.h"
#include "core/raycast/ray_scene.h"

namespace satmesh {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

struct GdalCloser {
  void operator()(GDALDataset* ds) const { GDALClose(GDALDataset::ToHandle(ds)); }
};
using GdalDatasetPtr = std::unique_ptr<GDALDataset, GdalCloser>;

std::string LastGdalError() {
  const char* msg = CPLGetLastErrorMsg();
  return (msg && *msg) ? std::string(": ") + msg : std::string();
}

// Every GDAL failure message raised while it lives, in order (GDAL keeps only the last:
// a write that fails for lack of space can be followed by a libtiff error that no longer
// says why, e.g. "TIFFReadDirectory: Failed to read directory").
class GdalErrorCollector {
 public:
  GdalErrorCollector() { CPLPushErrorHandlerEx(&Collect, this); }
  ~GdalErrorCollector() { CPLPopErrorHandler(); }
  GdalErrorCollector(const GdalErrorCollector&) = delete;
  GdalErrorCollector& operator=(const GdalErrorCollector&) = delete;
  // ": first; ...; last" or "" when none.
  std::string Joined() const {
    std::string out;
    for (const auto& m : messages_) out += (out.empty() ? ": " : "; ") + m;
    return out;
  }

 private:
  static void CPL_STDCALL Collect(CPLErr level, CPLErrorNum, const char* msg) {
    auto* self = static_cast<GdalErrorCollector*>(CPLGetErrorHandlerUserData());
    if (level >= CE_Failure && self && msg) self->messages_.emplace_back(msg);
  }
  std::vector<std::string> messages_;
};

void CheckNorthUp(const std::array<double, 6>& gt, const std::string& what) {
  SATMESH_CHECK(gt[2] == 0.0 && gt[4] == 0.0, ErrorCode::kInvalidInput,
                what + ": rotated/sheared grids are not supported (geotransform terms " +
                    std::to_string(gt[2]) + ", " + std::to_string(gt[4]) + ")");
  SATMESH_CHECK(gt[1] != 0.0 && gt[5] != 0.0 && std::isfinite(gt[1]) && std::isfinite(gt[5]),
                ErrorCode::kInvalidInput, what + ": degenerate cell size in geotransform");
}

Ray VerticalRay(float x, float y, float z_start) {
  return Ray{{x, y, z_start}, {0, 0, -1}, 0.f, std::numeric_limits<float>::infinity()};
}

// Height of a hit, interpolated from the face's vertices (more exact than z_start - t).
double HitZ(const TriangleMesh& mesh, const RayHit& hit) {
  const Eigen::Vector3i& f = mesh.faces[hit.face];
  return (1.0 - hit.u - hit.v) * mesh.vertices[f[0]].z() +
         double(hit.u) * mesh.vertices[f[1]].z() + double(hit.v) * mesh.vertices[f[2]].z();
}

// Height of face f's plane at (x, y) (local), or NaN for a (near-)vertical face.
double PlaneZ(const TriangleMesh& mesh, int face, double x, double y) {
  const Eigen::Vector3i& f = mesh.faces[face];
  const Eigen::Vector3d p0 = mesh.vertices[f[0]].cast<double>();
  const Eigen::Vector3d e1 = mesh.vertices[f[1]].cast<double>() - p0;
  const Eigen::Vector3d e2 = mesh.vertices[f[2]].cast<double>() - p0;
  const Eigen::Vector3d n(e1.y() * e2.z() - e1.z() * e2.y(), e1.z() * e2.x() - e1.x() * e2.z(),
                          e1.x() * e2.y() - e1.y() * e2.x());
  if (std::abs(n.z()) < 1e-3 * n.norm()) return std::numeric_limits<double>::quiet_NaN();
  return p0.z() - (n.x() * (x - p0.x()) + n.y() * (y - p0.y())) / n.z();
}

// A ray exactly through a vertex or edge on the mesh boundary may miss by float rounding
// (e.g. every boundary cell of a DSM mesh). Retry such rays offset by delta in 8
// directions (22.5 + k*45 degrees, never along a grid axis or diagonal) and take the
// highest hit, evaluated on the hit face's plane at the exact (x, y).
void RetryOnBoundary(const TriangleMesh& mesh, const RayScene& scene,
                     const std::vector<Ray>& rays, const std::vector<size_t>& missed,
                     float delta, float* z_out) {
  constexpr int kDirs = 8;
  std::vector<Ray> retry(missed.size() * kDirs);
  for (size_t m = 0; m < missed.size(); ++m) {
    const Ray& r = rays[missed[m]];
    for (int d = 0; d < kDirs; ++d) {
      const double angle = (22.5 + 45.0 * d) * std::numbers::pi / 180.0;
      retry[m * kDirs + d] =
          VerticalRay(r.origin.x() + delta * float(std::cos(angle)),
                      r.origin.y() + delta * float(std::sin(angle)), r.origin.z());
    }
  }
  std::vector<RayHit> hits(retry.size());
  scene.Intersect(retry.data(), hits.data(), retry.size());
  for (size_t m = 0; m < missed.size(); ++m) {
    const Ray& r = rays[missed[m]];
    double best = -std::numeric_limits<double>::infinity();
    for (int d = 0; d < kDirs; ++d) {
      const RayHit& hit = hits[m * kDirs + d];
      if (!hit.hit()) continue;
      double z = PlaneZ(mesh, hit.face, r.origin.x(), r.origin.y());
      if (std::isnan(z)) z = HitZ(mesh, hit);
      best = std::max(best, z);
    }
    if (std::isfinite(best)) z_out[missed[m]] = float(mesh.origin.z() + best);
  }
}

// Warns when both CRSs are known and differ (the caller must pass matching ones).
void WarnIfCrsDiffers(const std::string& mesh_crs, const std::string& grid_crs) {
  if (mesh_crs.empty() || grid_crs.empty() || mesh_crs == grid_crs) return;
  EnsureGdalInitialized();
  OGRSpatialReference a, b;
  if (a.SetFromUserInput(mesh_crs.c_str()) != OGRERR_NONE ||
      b.SetFromUserInput(grid_crs.c_str()) != OGRERR_NONE || !a.IsSame(&b)) {
    spdlog::warn("DsmFromMesh: the mesh's CRS differs from the grid's; using the mesh's "
                 "coordinates as if they were in the grid's CRS");
  }
}

// Orders (a, b, c) counter-clockwise seen from +z, given 2D positions.
Eigen::Vector3i CounterClockwise(int a, int b, int c, const Eigen::Vector2d& pa,
                                 const Eigen::Vector2d& pb, const Eigen::Vector2d& pc) {
  const double cross = (pb - pa).x() * (pc - pa).y() - (pb - pa).y() * (pc - pa).x();
  return cross >= 0 ? Eigen::Vector3i(a, b, c) : Eigen::Vector3i(a, c, b);
}

}  // namespace

Dsm ReadDsm(const std::string& path) {
  EnsureGdalInitialized();
  VSIStatBufL stat;
  SATMESH_CHECK(VSIStatL(path.c_str(), &stat) == 0 || path.rfind("/vsi", 0) == 0,
                ErrorCode::kNotFound, "DSM file not found: " + path);
  GdalDatasetPtr ds(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  SATMESH_CHECK(ds != nullptr, ErrorCode::kInvalidInput,
                "cannot open DSM " + path + LastGdalError());
  SATMESH_CHECK(ds->GetRasterCount() >= 1, ErrorCode::kInvalidInput,
                "DSM " + path + " has no raster band");
  Dsm dsm;
  dsm.width = ds->GetRasterXSize();
  dsm.height = ds->GetRasterYSize();
  SATMESH_CHECK(ds->GetGeoTransform(dsm.geo_transform.data()) == CE_None,
                ErrorCode::kInvalidInput, "DSM " + path + " has no geotransform");
  CheckNorthUp(dsm.geo_transform, "DSM " + path);
  const char* wkt = ds->GetProjectionRef();
  dsm.crs_wkt = wkt ? wkt : "";
  if (dsm.crs_wkt.empty()) spdlog::warn("DSM {} has no CRS", path);

  dsm.z.resize(size_t(dsm.width) * dsm.height);
  GDALRasterBand* band = ds->GetRasterBand(1);
  SATMESH_CHECK(band->RasterIO(GF_Read, 0, 0, dsm.width, dsm.height, dsm.z.data(), dsm.width,
                               dsm.height, GDT_Float32, 0, 0, nullptr) == CE_None,
                ErrorCode::kIo, "reading DSM " + path + " failed" + LastGdalError());
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  const float nodata_f = static_cast<float>(nodata);
  for (float& z : dsm.z) {
    if (!std::isfinite(z) || (has_nodata && z == nodata_f)) z = kNaN;
  }
  return dsm;
}

void WriteDsm(const std::string& path, const Dsm& dsm) {
  EnsureGdalInitialized();
  SATMESH_CHECK(dsm.width > 0 && dsm.height > 0 &&
                    dsm.z.size() == size_t(dsm.width) * size_t(dsm.height),
                ErrorCode::kInvalidArgument,
                "WriteDsm " + path + ": z has " + std::to_string(dsm.z.size()) +
                    " values for a " + std::to_string(dsm.width) + "x" +
                    std::to_string(dsm.height) + " grid");
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  SATMESH_CHECK(driver != nullptr, ErrorCode::kInternal, "GDAL GTiff driver missing");
  GdalErrorCollector errors;
  CPLStringList options;
  options.SetNameValue("TILED", "YES");
  options.SetNameValue("COMPRESS", "DEFLATE");
  options.SetNameValue("PREDICTOR", "3");  // floating-point predictor
  options.SetNameValue("BIGTIFF", "IF_SAFER");
  GdalDatasetPtr ds(
      driver->Create(path.c_str(), dsm.width, dsm.height, 1, GDT_Float32, options.List()));
  SATMESH_CHECK(ds != nullptr, ErrorCode::kIo, "cannot create DSM " + path + LastGdalError());
  std::array<double, 6> gt = dsm.geo_transform;
  ds->SetGeoTransform(gt.data());
  if (!dsm.crs_wkt.empty()) {
    SATMESH_CHECK(ds->SetProjection(dsm.crs_wkt.c_str()) == CE_None, ErrorCode::kInvalidInput,
                  "WriteDsm " + path + ": invalid CRS" + LastGdalError());
  }
  GDALRasterBand* band = ds->GetRasterBand(1);
  band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
  bool ok = band->RasterIO(GF_Write, 0, 0, dsm.width, dsm.height, const_cast<float*>(dsm.z.data()),
                           dsm.width, dsm.height, GDT_Float32, 0, 0, nullptr) == CE_None;
  if (ok) {
    ds->FlushCache();
    ok = CPLGetLastErrorType() < CE_Failure;
  }
  if (!ok) {  // a full disk is kNoSpace (the server waits for space), anything else kIo
    ds.reset();  // closing writes the directory: its errors are part of the story
    const std::string message = "writing DSM " + path + " failed" + errors.Joined();
    ThrowError(WriteErrorCode(message), message);
  }
}

TriangleMesh MeshFromDsm(const Dsm& dsm) {
  CheckNorthUp(dsm.geo_transform, "MeshFromDsm");
  SATMESH_CHECK(dsm.z.size() == size_t(dsm.width) * size_t(dsm.height),
                ErrorCode::kInvalidArgument, "MeshFromDsm: z size does not match the grid");
  const int w = dsm.width, h = dsm.height;
  auto valid = [&](int i, int j) { return std::isfinite(dsm.at(i, j)); };
  TriangleMesh mesh;
  mesh.crs = dsm.crs_wkt;
  float z_min = std::numeric_limits<float>::infinity(), z_max = -z_min;
  for (float z : dsm.z) {
    if (std::isfinite(z)) z_min = std::min(z_min, z), z_max = std::max(z_max, z);
  }
  const double z_mid = std::isfinite(z_min) ? 0.5 * (double(z_min) + z_max) : 0.0;
  const auto& gt = dsm.geo_transform;
  mesh.origin = Eigen::Vector3d(std::round(gt[0] + 0.5 * w * gt[1]),
                                std::round(gt[3] + 0.5 * h * gt[5]), std::round(z_mid));

  // Vertex ids are created on first use, so cells in no triangle make no vertex.
  std::vector<int> vertex_of(dsm.z.size(), -1);
  auto vertex = [&](int i, int j) {
    int& id = vertex_of[size_t(j) * w + i];
    if (id < 0) {
      id = static_cast<int>(mesh.vertices.size());
      mesh.vertices.emplace_back(float(dsm.CellCenterX(i) - mesh.origin.x()),
                                 float(dsm.CellCenterY(j) - mesh.origin.y()),
                                 float(double(dsm.at(i, j)) - mesh.origin.z()));
    }
    return id;
  };
  // 2D positions in index space scaled by the cell size (sign decides the winding).
  auto pos = [&](int i, int j) { return Eigen::Vector2d(i * gt[1], j * gt[5]); };
  auto add = [&](int ia, int ja, int ib, int jb, int ic, int jc) {
    mesh.faces.push_back(CounterClockwise(vertex(ia, ja), vertex(ib, jb), vertex(ic, jc),
                                          pos(ia, ja), pos(ib, jb), pos(ic, jc)));
  };
  for (int j = 0; j + 1 < h; ++j) {
    for (int i = 0; i + 1 < w; ++i) {
      // a b
      // c d
      const bool va = valid(i, j), vb = valid(i + 1, j), vc = valid(i, j + 1),
                 vd = valid(i + 1, j + 1);
      const int n = va + vb + vc + vd;
      if (n == 4) {
        const float ad = std::abs(dsm.at(i, j) - dsm.at(i + 1, j + 1));
        const float bc = std::abs(dsm.at(i + 1, j) - dsm.at(i, j + 1));
        if (ad <= bc) {
          add(i, j, i + 1, j + 1, i, j + 1);
          add(i, j, i + 1, j, i + 1, j + 1);
        } else {
          add(i, j, i + 1, j, i, j + 1);
          add(i + 1, j, i + 1, j + 1, i, j + 1);
        }
      } else if (n == 3) {
        if (!va) add(i + 1, j, i + 1, j + 1, i, j + 1);
        else if (!vb) add(i, j, i + 1, j + 1, i, j + 1);
        else if (!vc) add(i, j, i + 1, j, i + 1, j + 1);
        else add(i, j, i + 1, j, i, j + 1);
      }
    }
  }
  return mesh;
}

namespace {

// The grid's cells seen from above: `value(hit)` of the topmost face under each cell
// centre (NaN where none). retry_boundary: rays that miss are retried off the boundary
// (RetryOnBoundary, heights only).
template <typename ValueFn>
Dsm RasterizeFromAbove(const TriangleMesh& mesh, const Dsm& grid, const RayScene* given_scene,
                       ValueFn value, bool retry_boundary) {
  CheckNorthUp(grid.geo_transform, "DsmFromMesh grid");
  SATMESH_CHECK(grid.width >= 0 && grid.height >= 0, ErrorCode::kInvalidArgument,
                "DsmFromMesh: negative grid size");
  Dsm out;
  out.width = grid.width;
  out.height = grid.height;
  out.geo_transform = grid.geo_transform;
  out.crs_wkt = grid.crs_wkt;
  out.z.assign(size_t(out.width) * out.height, kNaN);
  if (mesh.faces.empty() || out.z.empty()) return out;
  WarnIfCrsDiffers(mesh.crs, grid.crs_wkt);

  std::optional<RayScene> own;  // built here unless given: validates indices and finiteness
  const RayScene& scene = given_scene ? *given_scene : own.emplace(mesh);
  float top = -std::numeric_limits<float>::infinity();
  float extent = 0.f;
  for (const auto& v : mesh.vertices) {
    top = std::max(top, v.z());
    extent = std::max({extent, std::abs(v.x()), std::abs(v.y())});
  }
  const float z_start = top + 1.f + 1e-3f * std::abs(top);
  const double cell = std::min(std::abs(grid.geo_transform[1]), std::abs(grid.geo_transform[5]));
  // Boundary retry offset: far below the cell size, far above float rounding.
  const float delta = std::max(float(1e-3 * cell),
                               64.f * std::numeric_limits<float>::epsilon() * extent);

  // Rows in chunks of ~1M rays to bound memory on large grids.
  const int rows_per_chunk = std::max(1, (1 << 20) / std::max(1, out.width));
  std::vector<Ray> rays;
  std::vector<RayHit> hits;
  for (int j0 = 0; j0 < out.height; j0 += rows_per_chunk) {
    const int j1 = std::min(out.height, j0 + rows_per_chunk);
    rays.resize(size_t(j1 - j0) * out.width);
    for (int j = j0; j < j1; ++j) {
      const float y = float(out.CellCenterY(j) - mesh.origin.y());
      for (int i = 0; i < out.width; ++i) {
        const float x = float(out.CellCenterX(i) - mesh.origin.x());
        rays[size_t(j - j0) * out.width + i] = VerticalRay(x, y, z_start);
      }
    }
    hits.resize(rays.size());
    scene.Intersect(rays.data(), hits.data(), rays.size());
    std::vector<size_t> missed;
    for (size_t k = 0; k < hits.size(); ++k) {
      if (hits[k].hit()) {
        out.z[size_t(j0) * out.width + k] = value(hits[k]);
      } else {
        missed.push_back(k);
      }
    }
    if (retry_boundary)
      RetryOnBoundary(mesh, scene, rays, missed, delta, out.z.data() + size_t(j0) * out.width);
  }
  return out;
}

}  // namespace

Dsm DsmFromMesh(const TriangleMesh& mesh, const Dsm& grid, const RayScene* scene) {
  return RasterizeFromAbove(
      mesh, grid, scene,
      [&](const RayHit& hit) { return float(mesh.origin.z() + HitZ(mesh, hit)); },
      /*retry_boundary=*/true);
}

Dsm HeightSigmaFromMesh(const TriangleMesh& mesh, const Dsm& grid, const RayScene* scene) {
  SATMESH_CHECK(mesh.height_sigma.size() == mesh.vertices.size(), ErrorCode::kInvalidArgument,
                "HeightSigmaFromMesh: the mesh has no height_sigma per vertex");
  return RasterizeFromAbove(
      mesh, grid, scene,
      [&](const RayHit& hit) {
        const Eigen::Vector3i& f = mesh.faces[hit.face];
        const float a = mesh.height_sigma[f[0]], b = mesh.height_sigma[f[1]],
                    c = mesh.height_sigma[f[2]];
        if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c))
          return std::numeric_limits<float>::infinity();  // a corner no image sees
        return (1.f - hit.u - hit.v) * a + hit.u * b + hit.v * c;
      },
      /*retry_boundary=*/false);
}

double DsmCellNoise(const Dsm& dsm) {
  std::vector<float> d;
  d.reserve(2 * dsm.z.size());
  const auto add = [&](float a, float b, float c) {
    const float v = a - 2 * b + c;
    if (std::isfinite(v)) d.push_back(v);
  };
  for (int j = 0; j < dsm.height; ++j)
    for (int i = 0; i < dsm.width; ++i) {
      if (i > 0 && i + 1 < dsm.width) add(dsm.at(i - 1, j), dsm.at(i, j), dsm.at(i + 1, j));
      if (j > 0 && j + 1 < dsm.height) add(dsm.at(i, j - 1), dsm.at(i, j), dsm.at(i, j + 1));
    }
  if (d.size() < 100) return std::numeric_limits<double>::quiet_NaN();
  const auto median = [](std::vector<float>* v) {
    auto mid = v->begin() + long(v->size() / 2);
    std::nth_element(v->begin(), mid, v->end());
    return double(*mid);
  };
  const double centre = median(&d);
  for (float& v : d) v = float(std::abs(v - centre));
  return 1.4826 * median(&d) / std::sqrt(6.0);
}

}  // namespace satmesh
