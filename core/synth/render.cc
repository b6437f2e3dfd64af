#include "core/synth/render.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/common/error.h"
#include "core/geo/crs.h"

namespace satmesh::synth {
namespace {
constexpr double kDeg = M_PI / 180.0;
constexpr int kLanes = 16;

// 16 rays for rtcIntersect16/rtcOccluded16. Lanes not Set stay inactive with finite,
// harmless values (Embree is built with ray masks: mask must be non-zero; it aborts on NaN).
struct Packet {
  alignas(64) int valid[kLanes] = {};
  RTCRayHit16 rh;
  bool any = false;

  Packet() {
    for (int k = 0; k < kLanes; ++k) {
      auto& r = rh.ray;
      r.org_x[k] = r.org_y[k] = r.org_z[k] = 0.f;
      r.dir_x[k] = r.dir_y[k] = 0.f;
      r.dir_z[k] = 1.f;
      r.tnear[k] = 0.f;
      r.tfar[k] = 0.f;
      r.time[k] = 0.f;
      r.mask[k] = 0xFFFFFFFFu;
      r.id[k] = unsigned(k);
      r.flags[k] = 0;
      rh.hit.geomID[k] = rh.hit.primID[k] = rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
  }
  void Set(int k, const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_near, float t_far) {
    if (!o.allFinite() || !d.allFinite() || !(d.squaredNorm() > 0.f)) return;
    auto& r = rh.ray;
    r.org_x[k] = o.x(), r.org_y[k] = o.y(), r.org_z[k] = o.z();
    r.dir_x[k] = d.x(), r.dir_y[k] = d.y(), r.dir_z[k] = d.z();
    r.tnear[k] = t_near, r.tfar[k] = t_far;
    valid[k] = -1;
    any = true;
  }
  void Intersect(RTCScene scene) {
    if (!any) return;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcIntersect16(valid, scene, &context, &rh);
  }
  void Occluded(RTCScene scene) {  // tfar becomes -inf on occluded lanes
    if (!any) return;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    rtcOccluded16(valid, scene, &context, &rh.ray);
  }
  bool Hit(int k) const { return valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID; }
  bool Blocked(int k) const { return valid[k] && !(rh.ray.tfar[k] >= 0.f); }
};
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

struct RenderScene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

RenderScene::RenderScene(const CityModel& city) : city_(city), impl_(std::make_unique<Impl>()) {
  const TriangleMesh& mesh = city.mesh;
  normals_.reserve(mesh.faces.size());
  for (const auto& f : mesh.faces) {
    const auto &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
    const Eigen::Vector3f n = (b - a).cross(c - a);
    normals_.push_back(n.norm() > 0 ? n.normalized() : Eigen::Vector3f(0, 0, 1));
  }
  for (const auto& v : mesh.vertices)
    SATMESH_CHECK(v.allFinite(), ErrorCode::kInvalidInput, "RenderScene: non-finite vertex");
  impl_->device = rtcNewDevice(nullptr);
  SATMESH_CHECK(impl_->device != nullptr, ErrorCode::kInternal, "RenderScene: rtcNewDevice failed");
  impl_->scene = rtcNewScene(impl_->device);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_HIGH);  // static: built once, traced a lot
  if (!mesh.faces.empty()) {
    RTCGeometry g = rtcNewGeometry(impl_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), mesh.faces.size()));
    SATMESH_CHECK(vb && ib, ErrorCode::kInternal, "RenderScene: Embree could not allocate buffers");
    const long long nv = (long long)mesh.vertices.size();
    for (size_t i = 0; i < mesh.vertices.size(); ++i)
      for (int k = 0; k < 3; ++k) vb[3 * i + k] = mesh.vertices[i][k];
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        SATMESH_CHECK(mesh.faces[f][k] >= 0 && mesh.faces[f][k] < nv, ErrorCode::kInvalidInput,
                      "RenderScene: face " + std::to_string(f) + " has a vertex out of range");
        ib[3 * f + k] = unsigned(mesh.faces[f][k]);
      }
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
    rtcCommitGeometry(g);
    rtcAttachGeometry(impl_->scene, g);
    rtcReleaseGeometry(g);  // the scene holds it
  }
  rtcCommitScene(impl_->scene);
}

RenderScene::~RenderScene() = default;

void RenderScene::Intersect(const Ray* rays, RayHit* hits, size_t n) const {
  const long long packets = (long long)((n + kLanes - 1) / kLanes);
#pragma omp parallel for schedule(dynamic, 64)
  for (long long p = 0; p < packets; ++p) {
    Packet pk;
    for (int k = 0; k < kLanes; ++k) {
      const size_t i = size_t(p) * kLanes + k;
      if (i < n) pk.Set(k, rays[i].origin, rays[i].direction, rays[i].t_near, rays[i].t_far);
    }
    pk.Intersect(impl_->scene);
    for (int k = 0; k < kLanes; ++k) {
      const size_t i = size_t(p) * kLanes + k;
      if (i >= n) continue;
      hits[i] = RayHit{};
      if (pk.Hit(k)) hits[i] = {int(pk.rh.hit.primID[k]), pk.rh.ray.tfar[k], pk.rh.hit.u[k], pk.rh.hit.v[k]};
    }
  }
}

std::string RenderOptions::Check() const {
  if (supersample < 1 || supersample > 8) return "supersample must be in [1, 8]";
  if (!(sun_irradiance > 0) || !(sky_irradiance >= 0)) return "irradiances must be positive";
  if (row_block < 1) return "row_block must be >= 1";
  return "";
}

// Pixels are traced in 4x4 blocks: one packet of 16 primary rays per subsample (coherent:
// neighbouring pixels), then one packet of shadow rays for the lanes whose surface faces
// the sun, then shading; everything on the stack, no allocation per pixel.
ImageF RenderView(const RenderScene& scene, const ViewRayGrid& rays, int width, int height,
                  const SunLight& sun, const RenderOptions& options, const Progress* progress) {
  const std::string why = options.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "RenderOptions: " + why);
  const int s = options.supersample;
  const Eigen::Vector3f to_sun = sun.DirectionToSun();
  const CityModel& city = scene.city();
  const auto& normals = scene.face_normals();
  const RTCScene rtc = scene.impl().scene;
  ImageF out(width, height, 0.f);
  const int band = std::max(4, options.row_block / 4 * 4);
  const int blocks_x = (width + 3) / 4;
  for (int r0 = 0; r0 < height; r0 += band) {
    if (progress) progress->ThrowIfCancelled();
    const int r1 = std::min(height, r0 + band);
    const int blocks = blocks_x * ((r1 - r0 + 3) / 4);
#pragma omp parallel for schedule(dynamic, 4)
    for (int b = 0; b < blocks; ++b) {
      const int c0 = (b % blocks_x) * 4, row0 = r0 + (b / blocks_x) * 4;
      float sum[kLanes] = {};
      for (int q = 0; q < s * s; ++q) {
        const double dx = (q % s + 0.5) / s, dy = (q / s + 0.5) / s;
        Packet primary;
        for (int k = 0; k < kLanes; ++k) {
          const int col = c0 + (k & 3), row = row0 + (k >> 2);
          if (col >= width || row >= r1) continue;
          Eigen::Vector3d low, high;
          rays.Line(col + dx, row + dy, &low, &high);
          primary.Set(k, high.cast<float>(), (low - high).cast<float>(), 0.f, 1e30f);
        }
        primary.Intersect(rtc);
        Packet shadow;
        Eigen::Vector3f point[kLanes], normal[kLanes];
        for (int k = 0; k < kLanes; ++k) {
          if (!primary.Hit(k)) continue;
          const auto& r = primary.rh.ray;
          const Eigen::Vector3f dir(r.dir_x[k], r.dir_y[k], r.dir_z[k]);
          point[k] = Eigen::Vector3f(r.org_x[k], r.org_y[k], r.org_z[k]) + r.tfar[k] * dir;
          normal[k] = normals[primary.rh.hit.primID[k]];
          if (normal[k].dot(dir) > 0) normal[k] = -normal[k];
          if (normal[k].dot(to_sun) > 0) shadow.Set(k, point[k] + 0.01f * normal[k], to_sun, 0.f, 1e4f);
        }
        shadow.Occluded(rtc);
        for (int k = 0; k < kLanes; ++k) {
          if (!primary.valid[k]) continue;
          if (!primary.Hit(k)) {
            sum[k] += 0.1f;
            continue;
          }
          const unsigned f = primary.rh.hit.primID[k];
          const float albedo = Albedo(city.face_material[f], city.face_variant[f], point[k], normal[k], city.texture);
          const float direct = shadow.valid[k] && !shadow.Blocked(k) ? normal[k].dot(to_sun) : 0.f;
          const float sky = options.sky_irradiance * (0.55f + 0.45f * normal[k].z());
          sum[k] += albedo * (options.sun_irradiance * direct + sky);
        }
      }
      for (int k = 0; k < kLanes; ++k) {
        const int col = c0 + (k & 3), row = row0 + (k >> 2);
        if (col < width && row < r1) out.at(col, row) = sum[k] / float(s * s);
      }
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
