#include "core/geo/crs.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include <omp.h>

#include <cpl_conv.h>
#include <ogr_spatialref.h>

#include "core/common/error.h"
#include "core/common/gdal_init.h"

namespace satmesh {
namespace {

OGRSpatialReference ParseCrs(const std::string& crs) {
  EnsureGdalInitialized();
  OGRSpatialReference srs;
  SATMESH_CHECK(srs.SetFromUserInput(crs.c_str()) == OGRERR_NONE, ErrorCode::kInvalidInput,
                "unknown CRS '" + crs + "'");
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

// A 2D CRS is promoted to 3D (ellipsoidal height), so heights pass through a horizontal
// transform unchanged instead of being dropped or reinterpreted.
OGRSpatialReference ParseCrs3D(const std::string& crs) {
  OGRSpatialReference srs = ParseCrs(crs);
  if (!srs.IsCompound() && srs.GetAxesCount() == 2) srs.PromoteTo3D(nullptr);
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

}  // namespace

std::string CrsToWkt(const std::string& crs) {
  OGRSpatialReference srs = ParseCrs(crs);
  char* wkt = nullptr;
  const char* options[] = {"FORMAT=WKT2_2019", nullptr};
  SATMESH_CHECK(srs.exportToWkt(&wkt, options) == OGRERR_NONE, ErrorCode::kInvalidInput,
                "cannot export CRS '" + crs + "' to WKT");
  std::string out = wkt ? wkt : "";
  CPLFree(wkt);
  return out;
}

bool CrsIsGeographic(const std::string& crs) { return ParseCrs(crs).IsGeographic() != 0; }
bool CrsIsProjected(const std::string& crs) { return ParseCrs(crs).IsProjected() != 0; }

std::string UtmCrsAt(double lon_deg, double lat_deg) {
  const int zone = std::clamp(int(std::floor((lon_deg + 180.0) / 6.0)) + 1, 1, 60);
  return "EPSG:" + std::to_string((lat_deg >= 0 ? 32600 : 32700) + zone);
}

struct CrsTransform::Impl {
  OGRSpatialReference source, target;
  std::unique_ptr<OGRCoordinateTransformation> transform;
  std::string description;
};

CrsTransform::CrsTransform(const std::string& source_crs, const std::string& target_crs)
    : impl_(std::make_unique<Impl>()) {
  impl_->source = ParseCrs3D(source_crs);
  impl_->target = ParseCrs3D(target_crs);
  impl_->description = "'" + source_crs + "' -> '" + target_crs + "'";
  impl_->transform.reset(OGRCreateCoordinateTransformation(&impl_->source, &impl_->target));
  SATMESH_CHECK(impl_->transform != nullptr, ErrorCode::kInvalidInput,
                "no coordinate transformation " + impl_->description);
}

CrsTransform::~CrsTransform() = default;
CrsTransform::CrsTransform(CrsTransform&&) noexcept = default;
CrsTransform& CrsTransform::operator=(CrsTransform&&) noexcept = default;

Eigen::Vector3d CrsTransform::Apply(const Eigen::Vector3d& point) const {
  double x = point.x(), y = point.y(), z = point.z();
  SATMESH_CHECK(impl_->transform->Transform(1, &x, &y, &z) != 0, ErrorCode::kInvalidInput,
                "CRS transform " + impl_->description + " failed for (" + std::to_string(point.x()) +
                    ", " + std::to_string(point.y()) + ", " + std::to_string(point.z()) + ")");
  return {x, y, z};
}

void CrsTransform::Apply(std::vector<Eigen::Vector3d>* points) const {
  const long n = long(points->size());
  if (n == 0) return;
  std::vector<double> x(n), y(n), z(n);
  std::vector<int> ok(n, 0);
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = (*points)[i];
    x[i] = p.x(), y[i] = p.y(), z[i] = p.z();
  }
  // A tile's mesh (hundreds of thousands of points, ~1 us each through PROJ) in one chunk
  // a thread, each through its own copy of the transformation (one is not to be shared
  // between threads; GDAL gives each thread its own PROJ context).
  constexpr long kPointsPerThread = 1 << 15;
  const int threads = int(std::clamp<long>(n / kPointsPerThread, 1, omp_get_max_threads()));
#pragma omp parallel num_threads(threads)
  {
    const int t = omp_get_thread_num(), team = omp_get_num_threads();
    const long begin = n * t / team, end = n * (t + 1) / team;
    std::unique_ptr<OGRCoordinateTransformation> own(t == 0 ? nullptr : impl_->transform->Clone());
    OGRCoordinateTransformation* transform = t == 0 ? impl_->transform.get() : own.get();
    if (transform && end > begin)
      transform->Transform(int(end - begin), x.data() + begin, y.data() + begin, z.data() + begin,
                           ok.data() + begin);
  }
  for (long i = 0; i < n; ++i) {
    SATMESH_CHECK(ok[i] != 0, ErrorCode::kInvalidInput,
                  "CRS transform " + impl_->description + " failed for point " + std::to_string(i));
    (*points)[i] = {x[i], y[i], z[i]};
  }
}

}  // namespace satmesh
