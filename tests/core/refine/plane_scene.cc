#include "tests/core/refine/plane_scene.h"

#include <algorithm>
#include <cmath>

#include "core/refine/virtual_camera.h"

namespace satmesh::testing {

double PlaneTexture(double x, double y, double z) {
  // Sum of rotated sinusoids with incommensurate wavelengths (not periodic in practice).
  const double waves[][3] = {{0.3, 1.7, 0.0}, {1.1, 2.3, 1.3}, {2.0, 3.1, 0.7},
                             {2.7, 4.3, 2.1}, {0.8, 5.9, 0.4}, {1.9, 1.3, 1.9}};
  double v = 0;
  for (const auto& w : waves) {
    const double u = std::cos(w[0]) * x + std::sin(w[0]) * y + 0.3 * z;
    v += std::sin(2 * M_PI * u / w[1] + w[2]);
  }
  return 0.5 + v / 12.0;
}

namespace {
RpcCoefficients AffineRpcCoefficients(const LocalFrame& frame, const ViewSpec& view,
                                      double gsd_m, int size_px) {
  RpcCoefficients c;
  const Eigen::Vector3d center = frame.center_lon_lat_h();
  c.long_off = center.x();
  c.lat_off = center.y();
  c.height_off = center.z();
  c.long_scale = c.lat_scale = 0.001;
  c.height_scale = 50;
  c.samp_off = c.line_off = 0.5 * size_px - 0.5;
  c.samp_scale = c.line_scale = 0.5 * size_px;
  const double sx = c.long_scale * frame.meters_per_degree_lon();  // metres per unit L
  const double sy = c.lat_scale * frame.meters_per_degree_lat();
  const double t = std::tan(view.off_nadir_deg * M_PI / 180.0);
  const double phi = view.azimuth_deg * M_PI / 180.0;
  // col - cx = (x - z t sinφ)/gsd ; row - cy = -(y - z t cosφ)/gsd
  c.samp_num[1] = sx / gsd_m / c.samp_scale;
  c.samp_num[3] = -c.height_scale * t * std::sin(phi) / gsd_m / c.samp_scale;
  c.line_num[2] = -sy / gsd_m / c.line_scale;
  c.line_num[3] = c.height_scale * t * std::cos(phi) / gsd_m / c.line_scale;
  c.samp_den[0] = c.line_den[0] = 1;
  return c;
}
}  // namespace

RpcModel AffineRpc(const LocalFrame& frame, const ViewSpec& view, double gsd_m, int size_px) {
  return RpcModel::FromCoefficients(AffineRpcCoefficients(frame, view, gsd_m, size_px));
}

RpcModel CurvedRpc(const LocalFrame& frame, const ViewSpec& view, double gsd_m, int size_px) {
  RpcCoefficients c = AffineRpcCoefficients(frame, view, gsd_m, size_px);
  for (int k = 4; k < 20; ++k) {
    c.samp_num[k] = 1e-2 * std::sin(k), c.line_num[k] = 1e-2 * std::cos(k);
    c.samp_den[k] = 3e-3 * std::cos(3 * k), c.line_den[k] = 3e-3 * std::sin(3 * k);
  }
  c.samp_den[1] = 2e-3, c.line_den[2] = -2e-3;
  return RpcModel::FromCoefficients(c);
}

ImageF RenderPlane(const RpcModel& rpc, const LocalFrame& frame, const Plane& plane, int size_px) {
  const VirtualCamera camera(rpc, frame, size_px, size_px, -30, 30, 8);
  ImageF image(size_px, size_px);
  for (int row = 0; row < size_px; ++row) {
    for (int col = 0; col < size_px; ++col) {
      double sum = 0;
      for (int sy = 0; sy < 3; ++sy) {
        for (int sx = 0; sx < 3; ++sx) {
          const Ray ray = camera.ExactRay(col + (sx + 0.5) / 3.0, row + (sy + 0.5) / 3.0);
          const Eigen::Vector3d o = ray.origin.cast<double>(), d = ray.direction.cast<double>();
          const double t = (plane.a * o.x() + plane.b * o.y() + plane.c - o.z()) /
                           (d.z() - plane.a * d.x() - plane.b * d.y());
          const Eigen::Vector3d p = o + t * d;
          sum += PlaneTexture(p.x(), p.y(), p.z());
        }
      }
      image.at(col, row) = float(200.0 + 1500.0 * sum / 9.0);
    }
  }
  return image;
}

TriangleMesh PlaneMesh(const Plane& plane, double half_m, double spacing_m, double dz) {
  TriangleMesh mesh;
  const int n = int(std::lround(2 * half_m / spacing_m)) + 1;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = -half_m + i * spacing_m, y = -half_m + j * spacing_m;
      mesh.vertices.emplace_back(float(x), float(y), float(plane.Z(x, y) + dz));
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const int v00 = j * n + i, v10 = v00 + 1, v01 = v00 + n, v11 = v01 + 1;
      mesh.faces.emplace_back(v00, v10, v11);  // counter-clockwise from above: normal up
      mesh.faces.emplace_back(v00, v11, v01);
    }
  }
  return mesh;
}

RefineInput MakePlaneInput(const Plane& plane, const std::vector<ViewSpec>& views,
                           const TriangleMesh& initial, int size_px, double gsd_m) {
  RefineInput input;
  input.frame = LocalFrame(Eigen::Vector3d(-81.66, 30.3, 10.0));
  for (size_t v = 0; v < views.size(); ++v) {
    RefineView view;
    view.name = "view" + std::to_string(v);
    view.rpc = AffineRpc(input.frame, views[v], gsd_m, size_px);
    view.image = RenderPlane(view.rpc, input.frame, plane, size_px);
    input.views.push_back(std::move(view));
  }
  input.initial_mesh = initial;
  input.min_z = -15;
  input.max_z = 20;
  return input;
}

std::vector<ViewSpec> DefaultViews() { return {{3, 0}, {10, 90}, {8, 200}}; }

std::pair<double, double> PlaneError(const TriangleMesh& mesh, const Plane& plane, double half) {
  std::vector<double> errors;
  for (const auto& v : mesh.vertices) {
    if (std::abs(v.x()) > half || std::abs(v.y()) > half) continue;
    errors.push_back(std::abs(v.z() - plane.Z(v.x(), v.y())));
  }
  if (errors.empty()) return {1e9, 1e9};
  double sum = 0;
  for (double e : errors) sum += e;
  std::sort(errors.begin(), errors.end());
  return {sum / errors.size(), errors[size_t(0.95 * (errors.size() - 1))]};
}

RefineOptions SmallOptions() {
  RefineOptions o;
  o.levels = 2;
  o.iterations_per_level = 15;
  o.estimate_bias = false;
  return o;
}

RefineOptions SmallOptionsTwoPairs() {
  RefineOptions o = SmallOptions();
  o.pairs.max_angle_deg = 13;
  o.pairs.optimal_angle_deg = 13;
  o.noise_variance_factor = 0;
  return o;
}

RefineInput PlaneWithInitialSurfaces(const Plane& plane, double coarse_off_m, double finer_off_m) {
  RefineInput input = MakePlaneInput(plane, DefaultViews(), PlaneMesh(plane, 40, 1.0, coarse_off_m));
  input.initial_for_edge = [plane, finer_off_m](double edge_m) {
    return PlaneMesh(plane, 40, 0.5 * edge_m, finer_off_m);
  };
  return input;
}

}  // namespace satmesh::testing
