#include "core/refine/view_setup.h"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>

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
  return out;
}

PhotometricOptions PhotometricOptionsAt(const RefineOptions& opt, double gsd_m) {
  PhotometricOptions photo;
  photo.zncc.window_radius = opt.zncc_window_radius;
  photo.zncc.min_valid_fraction = opt.min_window_valid;
  photo.zncc.variance_floor = opt.variance_floor;
  photo.visibility_tolerance_m = opt.visibility_tolerance_gsd * gsd_m;
  photo.min_ray_cos = opt.min_ray_cos;
  return photo;
}

}  // namespace satmesh
