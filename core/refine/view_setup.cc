#include "core/refine/view_setup.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/refine/view_level.h"
#include "core/refine/virtual_camera.h"

namespace satmesh {

double GroundSamplingDistance(const RpcModel& rpc, const LocalFrame& frame) {
  Eigen::Matrix<double, 2, 3> pixel_from_geo;
  rpc.PixelFromGeo(frame.center_lon_lat_h(), &pixel_from_geo);
  const Eigen::Matrix<double, 2, 3> pixel_from_local =
      pixel_from_geo * frame.GeoFromLocalScale().asDiagonal();
  const double det = std::abs(pixel_from_local.leftCols<2>().determinant());  // px² per m²
  return 1.0 / std::sqrt(det);
}

PairCandidateView MakePairCandidate(const RpcModel& rpc, const LocalFrame& frame,
                                    const ImageF& normalised, double min_z, double max_z) {
  PairCandidateView out;
  double sum = 0, sum2 = 0;
  for (float v : normalised.pixels) sum += v, sum2 += double(v) * v;
  const double n = double(std::max<size_t>(1, normalised.pixels.size()));
  out.contrast = std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
  const VirtualCamera camera(rpc, frame, normalised.width, normalised.height, min_z - 1,
                             max_z + 1, std::max(normalised.width, normalised.height));
  out.direction = camera.CentralDirection();
  const double z_mid = 0.5 * (min_z + max_z);
  for (double col : {0.0, double(normalised.width)})
    for (double row : {0.0, double(normalised.height)}) {
      const Ray ray = camera.PixelRay(col, row);
      if (std::abs(ray.direction.z()) < 1e-9) continue;
      const Eigen::Vector3d origin = ray.origin.cast<double>(), dir = ray.direction.cast<double>();
      out.footprint.extend((origin + (z_mid - origin.z()) / dir.z() * dir).head<2>());
    }
  return out;
}

std::vector<PreparedView> PrepareViews(const RefineInput& input, int levels) {
  std::vector<PreparedView> out(input.views.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long v = 0; v < long(input.views.size()); ++v) {
    const RefineView& view = input.views[v];
    PreparedView& p = out[v];
    p.pyramid = GaussianPyramid(NormalizeRadiometry(view.image), levels + 1);
    p.rpc = view.rpc;
    p.candidate = MakePairCandidate(view.rpc, input.frame, p.pyramid[0], input.min_z, input.max_z);
    constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
    p.candidate.sun_elevation_deg = view.acquisition.sun_elevation_deg.value_or(kUnknown);
    p.candidate.sun_azimuth_deg = view.acquisition.sun_azimuth_deg.value_or(kUnknown);
    p.candidate.time_s = view.acquisition.acquisition_unix_s.value_or(kUnknown);
    p.gsd_m = GroundSamplingDistance(view.rpc, input.frame);
    // Measured at full resolution, where noise dominates the finest texture; a pyramid
    // level averages ~4 pixels, dividing white noise's variance by ~4 (measuring the
    // coarse levels themselves would take their texture for noise).
    const double full_res = std::pow(NoiseSigma(p.pyramid[0]), 2);
    for (size_t level = 0; level < p.pyramid.size(); ++level)
      p.noise_variance.push_back(full_res * std::ldexp(1.0, -2 * int(level)));
  }
  return out;
}

double MeanNoiseVariance(const std::vector<PreparedView>& views, int level) {
  double sum = 0;
  int n = 0;
  for (const auto& v : views)
    if (level < int(v.noise_variance.size())) sum += v.noise_variance[level], ++n;
  return n > 0 ? sum / n : 0.0;
}

PairSelection SelectViewPairs(const RefineInput& input, const std::vector<PreparedView>& views,
                              const PairOptions& options) {
  Eigen::Vector3d box_min, box_max;
  SurfaceBox(input.initial_mesh, input.min_z, input.max_z, &box_min, &box_max);
  std::vector<PairCandidateView> candidates;
  for (const auto& v : views) candidates.push_back(v.candidate);
  return SelectPairs(candidates, Eigen::AlignedBox2d(box_min.head<2>(), box_max.head<2>()),
                     options);
}

PhotometricOptions PhotometricOptionsAt(const RefineOptions& opt, double gsd_m,
                                        double noise_variance) {
  PhotometricOptions photo;
  photo.zncc.window_radius = ResolveZnccWindowRadius(opt, 0);  // resolved by Refine, else 5x5
  photo.zncc.min_valid_fraction = opt.min_window_valid;
  photo.zncc.variance_floor = std::max(opt.variance_floor, opt.noise_variance_factor * noise_variance);
  photo.visibility_tolerance_m = opt.visibility_tolerance_gsd * gsd_m;
  photo.min_ray_cos = opt.min_ray_cos;
  return photo;
}

}  // namespace satmesh
