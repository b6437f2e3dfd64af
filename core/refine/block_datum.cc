#include "core/refine/block_datum.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/refine/photometric_gradient.h"
#include "core/refine/quadratic_step.h"
#include "core/refine/view_level.h"

namespace satmesh {
namespace {

// Mean ZNCC of `pairs` through the fixed initial surface with the whole block shifted by
// a horizontal ground vector t (metres, east-north): view v's RPC moved by J_v t. On a
// surface with relief (walls, roof edges) the images agree best where the block sits on
// it, which the relative biases alone do not fix (MinimumNormDatum). Over the middle of
// the surface, at most kDatumWindowPx full-resolution pixels across (each view's window
// cropped to it), for the cost; each shift builds the views' levels afresh (one Embree
// cast per view); values are cached.
class DatumObjective {
 public:
  static constexpr double kDatumWindowPx = 384;

  DatumObjective(const DatumProblem& pb, const std::vector<Eigen::Matrix2d>& jacobians,
                 const std::vector<std::pair<int, int>>& pairs, int level)
      : pb_(pb), jacobians_(jacobians), pairs_(pairs), level_(level),
        photo_(PhotometricOptionsAt(pb.options, pb.gsd_m * std::ldexp(1.0, level))) {
    // The middle of the surface's box, and each view's full-resolution window over it
    // (all heights; a margin for the shifts and the ZNCC window), aligned to the level.
    const Eigen::Vector3d centre = 0.5 * (pb.box_min + pb.box_max);
    const double half = 0.5 * kDatumWindowPx * pb.gsd_m;
    const Eigen::Vector2d box_lo = (centre.head<2>().array() - half).matrix().cwiseMax(pb.box_min.head<2>());
    const Eigen::Vector2d box_hi = (centre.head<2>().array() + half).matrix().cwiseMin(pb.box_max.head<2>());
    const int step = 1 << level;
    for (const auto& [a, b] : pairs)
      for (int v : {a, b}) {
        if (crops_.count(v)) continue;
        Eigen::Vector2d p_min(1e30, 1e30), p_max(-1e30, -1e30);
        for (int corner = 0; corner < 8; ++corner) {
          const Eigen::Vector3d local((corner & 1) ? box_hi.x() : box_lo.x(),
                                      (corner & 2) ? box_hi.y() : box_lo.y(),
                                      (corner & 4) ? pb.box_max.z() : pb.box_min.z());
          const Eigen::Vector2d px = pb.rpcs[v].PixelFromGeo(pb.frame.GeoFromLocal(local));
          p_min = p_min.cwiseMin(px), p_max = p_max.cwiseMax(px);
        }
        const ImageF& image = pb.views[v].pyramid[level];
        const double margin = 16 * step;
        const int c0 = std::max(0, int(std::floor((p_min.x() - margin) / step)));
        const int r0 = std::max(0, int(std::floor((p_min.y() - margin) / step)));
        const int c1 = std::min(image.width, int(std::ceil((p_max.x() + margin) / step)));
        const int r1 = std::min(image.height, int(std::ceil((p_max.y() + margin) / step)));
        Crop crop;
        crop.origin_px = Eigen::Vector2d(c0 * step, r0 * step);
        crop.image = ImageF(std::max(0, c1 - c0), std::max(0, r1 - r0));
        for (int r = 0; r < crop.image.height; ++r)
          std::copy_n(&image.pixels[size_t(r0 + r) * image.width + c0], crop.image.width,
                      &crop.image.pixels[size_t(r) * crop.image.width]);
        crops_.emplace(v, std::move(crop));
      }
  }

  double operator()(const Eigen::Vector2d& t) { return Evaluate({t}).front(); }

  std::vector<double> Evaluate(const std::vector<Eigen::Vector2d>& shifts) {
    std::vector<double> out;
    for (const Eigen::Vector2d& t : shifts) {
      const auto key = std::make_pair(std::lround(t.x() * 1e6), std::lround(t.y() * 1e6));
      auto it = cache_.find(key);
      if (it == cache_.end()) it = cache_.emplace(key, Compute(t)).first;
      out.push_back(it->second);
    }
    return out;
  }

 private:
  struct Crop {
    Eigen::Vector2d origin_px;  // full resolution, in the view's window
    ImageF image;               // at the level
  };

  double Compute(const Eigen::Vector2d& t) {
    std::map<int, ViewLevel> levels;
    for (const auto& [v, crop] : crops_) {
      if (crop.image.width < 16 || crop.image.height < 16) return -1.0;
      const RpcModel& rpc = pb_.rpcs[v];
      const RpcModel shifted = rpc.WithBias(rpc.bias() + jacobians_[v] * t).Cropped(crop.origin_px);
      ViewLevel level = MakeViewLevel(v, level_, crop.image, shifted, pb_.frame, pb_.box_min,
                                      pb_.box_max, pb_.options.virtual_camera_grid_px);
      CastHitMap(pb_.scene, &level, &pb_.normals);
      levels.emplace(v, std::move(level));
    }
    double sum = 0;
    long windows = 0;
    for (const auto& [a, b] : pairs_) {
      const PairEnergy e =
          AccumulatePairGradient(levels.at(a), levels.at(b), pb_.normals, photo_, nullptr, &workspace_);
      sum += e.sum_zncc;
      windows += e.num_windows;
    }
    return windows >= 16 ? sum / double(windows) : -1.0;
  }

  const DatumProblem& pb_;
  const std::vector<Eigen::Matrix2d>& jacobians_;
  std::vector<std::pair<int, int>> pairs_;
  int level_;
  PhotometricOptions photo_;
  std::map<int, Crop> crops_;
  PairWorkspace workspace_;
  std::map<std::pair<long, long>, double> cache_;
};

}  // namespace

std::vector<Eigen::Matrix2d> DatumJacobians(const std::vector<RpcModel>& rpcs,
                                            const LocalFrame& frame, const Eigen::Vector3d& center) {
  const Eigen::Vector3d geo = frame.GeoFromLocal(center);
  const Eigen::Vector3d scale = frame.GeoFromLocalScale();
  std::vector<Eigen::Matrix2d> jacobians;
  for (const RpcModel& rpc : rpcs) {
    Eigen::Matrix<double, 2, 3> j_geo;
    rpc.PixelFromGeo(geo, &j_geo);
    jacobians.push_back(j_geo.leftCols<2>() * scale.head<2>().asDiagonal());
  }
  return jacobians;
}

SurfaceDatumResult SurfaceDatum(const DatumProblem& pb, const std::vector<Eigen::Matrix2d>& jacobians,
                                const std::vector<std::pair<int, int>>& pairs,
                                const Eigen::Vector2d& t0, int coarse_level, const Progress& progress) {
  SurfaceDatumResult out;
  Eigen::Vector2d t = t0;
  const int upper = std::min(1, coarse_level);
  for (int level = upper; level >= 0; --level) {
    progress.ThrowIfCancelled();
    DatumObjective f(pb, jacobians, pairs, level);
    if (level == 0) out.zncc_before = f(t0);
    std::vector<double> steps_gsd;
    if (level > 0 || upper == 0) steps_gsd.insert(steps_gsd.end(), {1.0, 0.5});
    if (level == 0) steps_gsd.insert(steps_gsd.end(), {0.25, 0.125});
    for (double h : steps_gsd) t = QuadraticStep(f, t, h * pb.gsd_m);
    if (level == 0) out.zncc_after = f(t);
  }
  out.t = t;
  return out;
}

}  // namespace satmesh
