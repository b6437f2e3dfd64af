#include "core/eval/scene_views.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <filesystem>
#include <memory>

#include "core/common/error.h"
#include "core/geo/crs.h"
#include "core/image/image_io.h"
#include "core/rpc/rpc_io.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

std::vector<std::string> SceneImages(const std::string& images_dir) {
  namespace fs = std::filesystem;
  std::vector<std::string> paths;
  if (!fs::is_directory(images_dir)) return paths;
  for (const auto& entry : fs::directory_iterator(images_dir))
    if (entry.is_regular_file() && entry.path().extension() == ".tif")
      paths.push_back(entry.path().string());
  std::sort(paths.begin(), paths.end());
  return paths;
}

namespace {

struct SceneView {
  RpcModel rpc;
  int width = 0, height = 0;
};

}  // namespace

ViewDirectionsFn SceneViewDirections(const std::vector<std::string>& image_paths,
                                     const std::string& mesh_crs) {
  auto views = std::make_shared<std::vector<SceneView>>();
  for (const auto& path : image_paths) {
    const RasterInfo info = ReadRasterInfo(path);
    views->push_back({ReadRpc(path), info.width, info.height});
  }
  auto to_geo = std::make_shared<CrsTransform>(mesh_crs, kWgs84Geographic3D);
  return [views, to_geo](const std::vector<Eigen::Vector3d>& points) {
    ViewDirections out(views->size(), std::vector<Eigen::Vector3f>(points.size(), Eigen::Vector3f::Zero()));
    if (points.empty()) return out;
    std::vector<Eigen::Vector3d> geo = points;
    to_geo->Apply(&geo);
    // d(lon, lat, h)/d(x, y, z) at the points' centre: a scene is small against the
    // CRS's own distortion, so one Jacobian serves every point.
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const auto& p : points) centre += p;
    centre /= double(points.size());
    const Eigen::Vector3d g0 = to_geo->Apply(centre);
    Eigen::Matrix3d geo_from_crs;
    geo_from_crs.col(0) = to_geo->Apply(centre + Eigen::Vector3d::UnitX()) - g0;
    geo_from_crs.col(1) = to_geo->Apply(centre + Eigen::Vector3d::UnitY()) - g0;
    geo_from_crs.col(2) = to_geo->Apply(centre + Eigen::Vector3d::UnitZ()) - g0;
    for (size_t v = 0; v < views->size(); ++v) {
      const SceneView& view = (*views)[v];
#pragma omp parallel for schedule(static)
      for (size_t k = 0; k < points.size(); ++k) {
        Eigen::Matrix<double, 2, 3> pixel_from_geo;
        const Eigen::Vector2d px = view.rpc.PixelFromGeo(geo[k], &pixel_from_geo);
        if (!(px.x() >= 0 && px.y() >= 0 && px.x() < view.width && px.y() < view.height)) continue;
        const Eigen::Matrix<double, 2, 3> j = pixel_from_geo * geo_from_crs;
        Eigen::Vector3d d = Eigen::Vector3d(j.row(0)).cross(Eigen::Vector3d(j.row(1)));
        if (!(d.norm() > 0)) continue;
        d.normalize();
        if (d.z() < 0) d = -d;
        out[v][k] = d.cast<float>();
      }
    }
    return out;
  };
}

}  // namespace satmesh
