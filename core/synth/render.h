#pragma once
// Rendering of a textured scene (CityModel) through an exact pushbroom camera by Embree
// ray casting: procedural albedo, Lambertian sun + sky shading with cast shadows,
// supersampling; and the sensor model that turns radiance into 11-bit digital numbers.
#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/common/progress.h"
#include "core/image/image.h"
#include "core/raycast/ray_scene.h"
#include "core/synth/city.h"
#include "core/synth/pushbroom_camera.h"

namespace satmesh::synth {

struct SunLight {
  double azimuth_deg = 135;   // clockwise from north (grid north of the scene CRS)
  double elevation_deg = 60;  // above the horizon, (0, 90]
  Eigen::Vector3f DirectionToSun() const;  // unit, scene frame (x east, y north, z up)
};

// Lines of sight of a view in the scene frame (scene CRS minus the mesh origin), as the
// straight line through the exact camera's points at heights h_low and h_high, stored on
// a sparse pixel grid and interpolated bilinearly.
class ViewRayGrid {
 public:
  struct Options {
    int step_px = 16;       // grid node spacing, pixels, >= 1
    double h_low_m = -60;   // ellipsoidal heights of the two localisations, h_low < h_high
    double h_high_m = 80;
  };
  // scene_crs: e.g. "EPSG:32617"; origin: the scene frame's origin in that CRS.
  ViewRayGrid(const PushbroomCamera& camera, const std::string& scene_crs,
              const Eigen::Vector3d& origin, const Options& options);
  // Points of the line of sight of (col, row) at h_low and h_high, scene frame.
  void Line(double col, double row, Eigen::Vector3d* low, Eigen::Vector3d* high) const;
  const Options& options() const { return options_; }

 private:
  Options options_;
  int nx_ = 0, ny_ = 0;
  std::vector<Eigen::Vector3d> low_, high_;
};

// Max pixel error of the straight-line ray model: points on the interpolated lines at
// `heights_m` mapped back to the scene CRS / geodetic and projected by the exact camera,
// over a grid of `samples` x `samples` pixels.
double RayGridErrorPx(const PushbroomCamera& camera, const ViewRayGrid& rays,
                      const std::string& scene_crs, const Eigen::Vector3d& origin,
                      const std::vector<double>& heights_m, int samples = 9);

// A CityModel (or any mesh with per-face materials) prepared for ray casting: a static,
// high-quality Embree BVH (built once, shared by all views), and the face normals.
class RenderScene {
 public:
  explicit RenderScene(const CityModel& city);  // keeps a reference to city
  ~RenderScene();
  RenderScene(const RenderScene&) = delete;
  RenderScene& operator=(const RenderScene&) = delete;
  const CityModel& city() const { return city_; }
  const std::vector<Eigen::Vector3f>& face_normals() const { return normals_; }
  // Closest hits of n rays (parallel, packets of 16). Non-finite rays miss.
  void Intersect(const Ray* rays, RayHit* hits, size_t n) const;

  struct Impl;  // Embree device and scene (render.cc)
  const Impl& impl() const { return *impl_; }

 private:
  const CityModel& city_;
  std::unique_ptr<Impl> impl_;
  std::vector<Eigen::Vector3f> normals_;
};

struct RenderOptions {
  // Samples per pixel per axis (box filter), [1, 8]. A detector integrates the radiance over
  // its footprint; the textures' finest patterns (roof tiles, corrugation: periods under a
  // pixel) alias into each view differently when the pixel is point-sampled too coarsely.
  // At 2x2 a striped gable roof drew the refinement 2-4 m off the true surface even when it
  // started there (docs/benchmarks-history.md, session 42; stereo 0.5 m s1 from the true DSM:
  // roofs NMAD 0.172 m at 2x2, 0.128 at 6x6). 4x4 removes it on stereo at twice 2x2's render
  // time; tri-stereo's narrow pairs still draw that gable +2.6 m: the optics' blur
  // (SensorOptions::mtf_sigma_px) acts after sampling, not before as a real sensor's.
  int supersample = 4;
  float sun_irradiance = 1.0f;  // direct sun on a surface facing it, > 0
  float sky_irradiance = 0.3f;  // diffuse sky on an upward surface, >= 0
  int row_block = 32;           // rows per band (progress and cancellation), >= 1
  std::string Check() const;
};

// Radiance image (albedo x irradiance, about [0, 1.3]) of width x height pixels.
ImageF RenderView(const RenderScene& scene, const ViewRayGrid& rays, int width, int height,
                  const SunLight& sun, const RenderOptions& options = {},
                  const Progress* progress = nullptr);

struct SensorOptions {
  double gain = 1.0;            // per-image radiometric gain, > 0
  double offset_dn = 40;        // dark offset, DN, >= 0
  double full_scale = 1.3;      // radiance mapped to the top of the range (before gain), > 0
  double read_noise_dn = 3;     // Gaussian read noise, DN, >= 0
  double shot_noise = 0.05;     // shot noise variance per DN of signal, >= 0
  double mtf_sigma_px = 0.35;   // Gaussian optics/detector blur, pixels, >= 0 (0 = none)
  int bits = 11;                // output range [0, 2^bits - 1], [8, 16]
  std::string Check() const;
};
// Digital numbers (stored as floats with integer values) from radiance.
ImageF SimulateSensor(const ImageF& radiance, const SensorOptions& options, uint64_t seed);

}  // namespace satmesh::synth
