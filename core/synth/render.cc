#include "core/synth/render.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/common/error.h"
#include "core/geo/crs.h"

namespace satmesh::synth {
namespace {
constexpr double kDeg = M_PI / 180.0;
}  // namespace

Eigen::Vector3f SunLight::DirectionToSun() const {
  const double az = azimuth_deg * kDeg, el = elevation_deg * kDeg;
  return Eigen::Vector3d(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el))
      .cast<float>();
}

ViewRayGrid::ViewRayGrid(const PushbroomCamera& camera, const std::string& scene_crs,
                         const Eigen::Vector3d& origin, const Options& options)
    : options_(options) {
  SATMESH_CHECK(options.step_px >= 1 && options.h_low_m < options.h_high_m,
                ErrorCode::kInvalidArgument, "ViewRayGrid: need step_px >= 1, h_low < h_high");
  nx_ = (camera.width() + options.step_px - 1) / options.step_px + 2;
  ny_ = (camera.height() + options.step_px - 1) / options.step_px + 2;
  std::vector<Eigen::Vector3d> pts(size_t(nx_) * ny_ * 2);
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i)
      for (int k = 0; k < 2; ++k) {
        const double h = k ? options.h_high_m : options.h_low_m;
        auto g = camera.LocalizeAtHeight(
            Eigen::Vector2d(i * options.step_px, j * options.step_px), h);
        SATMESH_CHECK(g.has_value(), ErrorCode::kInternal,
                      "ViewRayGrid: line of sight does not reach the ground");
        pts[(size_t(j) * nx_ + i) * 2 + k] = Eigen::Vector3d(g->x(), g->y(), 0.0);
      }
  CrsTransform(kWgs84Geographic3D, scene_crs).Apply(&pts);
  low_.resize(size_t(nx_) * ny_);
  high_.resize(size_t(nx_) * ny_);
  for (size_t n = 0; n < low_.size(); ++n) {
    low_[n] = Eigen::Vector3d(pts[2 * n].x() - origin.x(), pts[2 * n].y() - origin.y(),
                              options.h_low_m - origin.z());
    high_[n] = Eigen::Vector3d(pts[2 * n + 1].x() - origin.x(), pts[2 * n + 1].y() - origin.y(),
                               options.h_high_m - origin.z());
  }
}

void ViewRayGrid::Line(double col, double row, Eigen::Vector3d* low, Eigen::Vector3d* high) const {
  const double u = std::clamp(col / options_.step_px, 0.0, nx_ - 1.000001);
  const double v = std::clamp(row / options_.step_px, 0.0, ny_ - 1.000001);
  const int i = int(u), j = int(v);
  const double fu = u - i, fv = v - j;
  const size_t n00 = size_t(j) * nx_ + i, n10 = n00 + 1, n01 = n00 + nx_, n11 = n01 + 1;
  const double w00 = (1 - fu) * (1 - fv), w10 = fu * (1 - fv), w01 = (1 - fu) * fv, w11 = fu * fv;
  *low = w00 * low_[n00] + w10 * low_[n10] + w01 * low_[n01] + w11 * low_[n11];
  *high = w00 * high_[n00] + w10 * high_[n10] + w01 * high_[n01] + w11 * high_[n11];
}

double RayGridErrorPx(const PushbroomCamera& camera, const ViewRayGrid& rays,
                      const std::string& scene_crs, const Eigen::Vector3d& origin,
                      const std::vector<double>& heights_m, int samples) {
  const auto& o = rays.options();
  std::vector<Eigen::Vector3d> pts;
  std::vector<Eigen::Vector3d> col_row_h;
  for (int j = 0; j < samples; ++j)
    for (int i = 0; i < samples; ++i) {
      // Off-node positions (interpolation is worst between nodes).
      const double col = (i + 0.37) * camera.width() / samples;
      const double row = (j + 0.61) * camera.height() / samples;
      Eigen::Vector3d low, high;
      rays.Line(col, row, &low, &high);
      for (double h : heights_m) {
        const double f = (h - o.h_low_m) / (o.h_high_m - o.h_low_m);
        const Eigen::Vector3d p = low + f * (high - low);
        pts.emplace_back(p.x() + origin.x(), p.y() + origin.y(), 0.0);
        col_row_h.emplace_back(col, row, h);
      }
    }
  CrsTransform(scene_crs, kWgs84Geographic3D).Apply(&pts);
  double worst = 0;
  for (size_t n = 0; n < pts.size(); ++n) {
    auto px = camera.PixelFromGeo(Eigen::Vector3d(pts[n].x(), pts[n].y(), col_row_h[n].z()));
    if (!px) return std::numeric_limits<double>::infinity();
    worst = std::max(worst, (*px - col_row_h[n].head<2>()).norm());
  }
  return worst;
}

RenderScene::RenderScene(const CityModel& city)
    : city_(city), ray_scene_(std::make_unique<RayScene>(city.mesh)) {
  normals_.reserve(city.mesh.faces.size());
  for (const auto& f : city.mesh.faces) {
    const auto &a = city.mesh.vertices[f[0]], &b = city.mesh.vertices[f[1]],
               &c = city.mesh.vertices[f[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    normals_.push_back(n.norm() > 0 ? n.normalized() : Eigen::Vector3f(0, 0, 1));
  }
}

std::string RenderOptions::Check() const {
  if (supersample < 1 || supersample > 8) return "supersample must be in [1, 8]";
  if (!(sun_irradiance > 0) || !(sky_irradiance >= 0)) return "irradiances must be positive";
  if (row_block < 1) return "row_block must be >= 1";
  return "";
}

ImageF RenderView(const RenderScene& scene, const ViewRayGrid& rays, int width, int height,
                  const SunLight& sun, const RenderOptions& options, const Progress* progress) {
  const std::string why = options.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "RenderOptions: " + why);
  const int s = options.supersample;
  const Eigen::Vector3f to_sun = sun.DirectionToSun();
  const CityModel& city = scene.city();
  ImageF out(width, height, 0.f);
  const size_t per_row = size_t(width) * s * s;
  std::vector<Ray> primary, shadow;
  std::vector<RayHit> hits;
  std::vector<unsigned char> occluded;
  std::vector<size_t> shadow_index;
  for (int r0 = 0; r0 < height; r0 += options.row_block) {
    if (progress) progress->ThrowIfCancelled();
    const int r1 = std::min(height, r0 + options.row_block);
    const size_t n = per_row * (r1 - r0);
    primary.resize(n);
    hits.resize(n);
    occluded.assign(n, 0);
#pragma omp parallel for schedule(dynamic, 1)
    for (int row = r0; row < r1; ++row)
      for (int col = 0; col < width; ++col)
        for (int b = 0; b < s; ++b)
          for (int a = 0; a < s; ++a) {
            Eigen::Vector3d low, high;
            rays.Line(col + (a + 0.5) / s, row + (b + 0.5) / s, &low, &high);
            Ray& ray = primary[(size_t(row - r0) * width + col) * s * s + b * s + a];
            ray.origin = high.cast<float>();
            ray.direction = (low - high).cast<float>();
            ray.t_near = 0.f;
            ray.t_far = 1e30f;
          }
    scene.rays().Intersect(primary.data(), hits.data(), n);
    // Shadow rays only where the sun can light the surface (compacted list).
    shadow.clear();
    shadow_index.clear();
    for (size_t k = 0; k < n; ++k) {
      if (!hits[k].hit()) continue;
      Eigen::Vector3f nrm = scene.face_normals()[hits[k].face];
      if (nrm.dot(primary[k].direction) > 0) nrm = -nrm;
      if (nrm.dot(to_sun) <= 0) continue;
      Ray sr;
      sr.origin = primary[k].origin + hits[k].t * primary[k].direction + 0.01f * nrm;
      sr.direction = to_sun;
      sr.t_near = 0.f;
      sr.t_far = 1e4f;
      shadow.push_back(sr);
      shadow_index.push_back(k);
    }
    std::vector<unsigned char> shadow_hit(shadow.size(), 0);
    scene.rays().Occluded(shadow.data(), shadow_hit.data(), shadow.size());
    for (size_t q = 0; q < shadow.size(); ++q) occluded[shadow_index[q]] = shadow_hit[q];
#pragma omp parallel for
    for (int row = r0; row < r1; ++row)
      for (int col = 0; col < width; ++col) {
        double sum = 0;
        for (int q = 0; q < s * s; ++q) {
          const size_t k = (size_t(row - r0) * width + col) * s * s + q;
          if (!hits[k].hit()) {
            sum += 0.1;
            continue;
          }
          const int f = hits[k].face;
          const Eigen::Vector3f p = primary[k].origin + hits[k].t * primary[k].direction;
          Eigen::Vector3f nrm = scene.face_normals()[f];
          if (nrm.dot(primary[k].direction) > 0) nrm = -nrm;
          const float albedo = Albedo(city.face_material[f], city.face_variant[f], p, nrm, city.texture);
          const float direct = occluded[k] ? 0.f : std::max(0.f, nrm.dot(to_sun));
          const float sky = options.sky_irradiance * (0.55f + 0.45f * nrm.z());
          sum += albedo * (options.sun_irradiance * direct + sky);
        }
        out.at(col, row) = float(sum / (s * s));
      }
    if (progress) progress->Report(double(r1) / height, "render");
  }
  return out;
}

std::string SensorOptions::Check() const {
  if (!(gain > 0) || !(full_scale > 0)) return "gain and full_scale must be > 0";
  if (!(offset_dn >= 0) || !(read_noise_dn >= 0) || !(shot_noise >= 0)) return "noise must be >= 0";
  if (!(mtf_sigma_px >= 0)) return "mtf_sigma_px must be >= 0";
  if (bits < 8 || bits > 16) return "bits must be in [8, 16]";
  return "";
}

ImageF SimulateSensor(const ImageF& radiance, const SensorOptions& o, uint64_t seed) {
  const std::string why = o.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "SensorOptions: " + why);
  ImageF blurred = radiance;
  if (o.mtf_sigma_px > 0) {
    cv::Mat src(radiance.height, radiance.width, CV_32F, const_cast<float*>(radiance.pixels.data()));
    cv::Mat dst(blurred.height, blurred.width, CV_32F, blurred.pixels.data());
    cv::GaussianBlur(src, dst, cv::Size(0, 0), o.mtf_sigma_px, o.mtf_sigma_px, cv::BORDER_REFLECT);
  }
  const double top = double((1 << o.bits) - 1);
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  ImageF out(radiance.width, radiance.height);
  for (size_t k = 0; k < out.pixels.size(); ++k) {
    const double signal = o.gain * blurred.pixels[k] / o.full_scale * (top - o.offset_dn);
    const double sigma = std::sqrt(o.read_noise_dn * o.read_noise_dn + o.shot_noise * std::max(0.0, signal));
    out.pixels[k] = float(std::clamp(std::round(o.offset_dn + signal + sigma * normal(gen)), 0.0, top));
  }
  return out;
}

}  // namespace satmesh::synth
