#include "core/refine/bias_estimation.h"

#include <Eigen/LU>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/common/error.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/pairs.h"
#include "core/mesh/topology.h"
#include "core/refine/photometric_gradient.h"
#include "core/refine/view_level.h"
#include "core/refine/view_setup.h"
#include "core/refine/virtual_camera.h"

namespace satmesh {
namespace {

std::string Num(double v) { return std::to_string(v); }

// The fixed part of the problem: pyramids, the initial surface and its ray scene.
struct Problem {
  const RefineInput& input;
  const BiasOptions& options;
  const std::vector<PreparedView>& views;    // pyramids, normalised
  std::vector<RpcModel> rpcs;                 // per view, with the biases solved so far
  const RayScene& scene;
  std::vector<Eigen::Vector3f> normals;
  Eigen::Vector3d box_min, box_max;
  double gsd_m = 0;
};

ViewLevel BuildLevel(const Problem& pb, int view, int level) {
  ViewLevel out = MakeViewLevel(view, level, pb.views[view].pyramid[level], pb.rpcs[view],
                                pb.input.frame, pb.box_min, pb.box_max,
                                pb.options.refine.virtual_camera_grid_px);
  CastHitMap(pb.scene, &out);
  return out;
}

// Mean ZNCC of the solved neighbours warped into `target` shifted by d (full-res px).
// The target's hit map for a shift is its unshifted one moved by the rounded level shift
// (a biased view's pixel q sees what the unbiased one sees at q - d).
class ShiftObjective {
 public:
  ShiftObjective(const Problem& pb, int target, const std::vector<int>& neighbours, int level)
      : pb_(pb), level_(level), base_rpc_(pb.rpcs[target]), target_(BuildLevel(pb, target, level)),
        photo_(PhotometricOptionsAt(pb.options.refine, pb.gsd_m * std::ldexp(1.0, level))) {
    base_hits_ = target_.hit_map;
    for (int n : neighbours) neighbours_.push_back(BuildLevel(pb, n, level));
  }

  double operator()(const Eigen::Vector2d& d) {
    const auto key = std::make_pair(std::lround(d.x() * 1e6), std::lround(d.y() * 1e6));
    if (auto it = cache_.find(key); it != cache_.end()) return it->second;
    const double scale = std::ldexp(1.0, -level_);
    target_.rpc = base_rpc_.WithBias(base_rpc_.bias() + d).AtLevel(level_);
    target_.projection = ProjectionGrid(target_.rpc, pb_.input.frame, pb_.box_min, pb_.box_max,
                                        /*spacing_xy_m=*/16.0, /*spacing_z_m=*/8.0);
    ShiftHitMap(int(std::lround(d.x() * scale)), int(std::lround(d.y() * scale)));
    double sum = 0;
    long windows = 0;
    for (const ViewLevel& n : neighbours_) {
      const PairEnergy e = AccumulatePhotometricGradient(n, target_, pb_.input.initial_mesh,
                                                         pb_.normals, photo_, nullptr, nullptr,
                                                         &workspace_);
      sum += e.sum_zncc;
      windows += e.num_windows;
    }
    const double value = windows >= 16 ? sum / double(windows) : -1.0;
    cache_[key] = value;
    return value;
  }

 private:
  void ShiftHitMap(int dx, int dy) {
    const int w = target_.width(), h = target_.height();
    HitMap& map = target_.hit_map;
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        const int c = col - dx, r = row - dy;
        const size_t p = size_t(row) * w + col;
        const bool inside = c >= 0 && r >= 0 && c < w && r < h;
        map.hits[p] = inside ? base_hits_.hits[size_t(r) * w + c] : RayHit{};
        map.surface[p] = inside ? base_hits_.surface[size_t(r) * w + c] : SurfacePoint{};
      }
    }
  }

  const Problem& pb_;
  int level_;
  RpcModel base_rpc_;
  ViewLevel target_;
  HitMap base_hits_;
  std::vector<ViewLevel> neighbours_;
  PhotometricOptions photo_;
  PairWorkspace workspace_;
  std::map<std::pair<long, long>, double> cache_;
};

// One 3x3 step at spacing h: a quadratic fit (least squares on the 9 values); its maximum
// if the fit is concave (clamped to +-h per axis), else the best of the 9.
Eigen::Vector2d QuadraticStep(ShiftObjective& f, const Eigen::Vector2d& d, double h) {
  double v[3][3];
  Eigen::Vector2d best = d;
  double best_value = -1e30;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector2d p = d + h * Eigen::Vector2d(i - 1, j - 1);
      v[j][i] = f(p);
      if (v[j][i] > best_value) best_value = v[j][i], best = p;
    }
  }
  double gx = 0, gy = 0, hxx = 0, hyy = 0;
  for (int k = 0; k < 3; ++k) {
    gx += (v[k][2] - v[k][0]) / (6 * h);
    gy += (v[2][k] - v[0][k]) / (6 * h);
    hxx += (v[k][2] - 2 * v[k][1] + v[k][0]) / (3 * h * h);
    hyy += (v[2][k] - 2 * v[1][k] + v[0][k]) / (3 * h * h);
  }
  const double hxy = (v[2][2] - v[0][2] - v[2][0] + v[0][0]) / (4 * h * h);
  Eigen::Matrix2d hessian;
  hessian << hxx, hxy, hxy, hyy;
  if (!(hxx < 0 && hessian.determinant() > 0)) return best;
  const Eigen::Vector2d step = (-hessian.inverse() * Eigen::Vector2d(gx, gy)).cwiseMax(-h).cwiseMin(h);
  const Eigen::Vector2d candidate = d + step;
  return f(candidate) >= best_value ? candidate : best;
}

// Coarse grid search, then 3x3 quadratic steps level by level down to full resolution.
Eigen::Vector2d SolveView(const Problem& pb, int view, const std::vector<int>& neighbours,
                          int coarse_level, const Progress& progress, double* zncc_before,
                          double* zncc_after) {
  const BiasOptions& o = pb.options;
  Eigen::Vector2d d(0, 0);
  for (int level = coarse_level; level >= 0; --level) {
    progress.ThrowIfCancelled();
    ShiftObjective f(pb, view, neighbours, level);
    if (level == coarse_level) {
      const int n = int(std::floor(o.search_radius_px / o.coarse_step_px));
      double best = -1e30;
      for (int j = -n; j <= n; ++j)
        for (int i = -n; i <= n; ++i) {
          const Eigen::Vector2d p = o.coarse_step_px * Eigen::Vector2d(i, j);
          if (const double v = f(p); v > best) best = v, d = p;
        }
      d = QuadraticStep(f, d, 0.5 * o.coarse_step_px);
    }
    if (level == 0) {
      *zncc_before = f(Eigen::Vector2d::Zero());
      for (double h = 0.5; h >= o.final_step_px * 0.999; h *= 0.5) d = QuadraticStep(f, d, h);
      *zncc_after = f(d);
    } else if (level < coarse_level) {
      d = QuadraticStep(f, d, 0.5 * std::ldexp(1.0, level));
    }
  }
  return d;
}

int ReferenceView(const std::vector<std::pair<int, int>>& pairs, int num_views, int requested) {
  if (requested >= 0) return requested;
  std::vector<int> count(num_views, 0);
  for (const auto& [a, b] : pairs) ++count[a], ++count[b];
  return int(std::max_element(count.begin(), count.end()) - count.begin());
}

}  // namespace

std::string BiasOptions::Check() const {
  if (coarse_level < 0 || coarse_level > 6) return "coarse_level must be in [0, 6], got " + Num(coarse_level);
  if (!(search_radius_px > 0)) return "search_radius_px must be > 0, got " + Num(search_radius_px);
  if (!(coarse_step_px > 0)) return "coarse_step_px must be > 0, got " + Num(coarse_step_px);
  if (!(final_step_px > 0)) return "final_step_px must be > 0, got " + Num(final_step_px);
  if (max_neighbours < 1) return "max_neighbours must be >= 1, got " + Num(max_neighbours);
  return refine.Check();
}

BiasEstimate EstimateViewBiases(const RefineInput& input,
                                const std::vector<std::pair<int, int>>& pairs,
                                const BiasOptions& options, const Progress& progress) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "bias options: " + problem);
  return EstimateViewBiases(input, PrepareViews(input, options.coarse_level), pairs, options,
                            progress);
}

BiasEstimate EstimateRefineBiases(const RefineInput& input, const BiasOptions& options,
                                  const Progress& progress) {
  const std::vector<PreparedView> views = PrepareViews(input, options.coarse_level);
  const PairSelection selection = SelectViewPairs(input, views, options.refine.pairs);
  SATMESH_CHECK(!selection.pairs.empty(), ErrorCode::kInvalidInput,
                "bias: no usable stereo pair: " + selection.refusal);
  return EstimateViewBiases(input, views, selection.IndexPairsBestFirst(), options, progress);
}

BiasEstimate EstimateViewBiases(const RefineInput& input, const std::vector<PreparedView>& views,
                                const std::vector<std::pair<int, int>>& pairs,
                                const BiasOptions& options, const Progress& progress) {
  const std::string problem = options.Check();
  SATMESH_CHECK(problem.empty(), ErrorCode::kInvalidArgument, "bias options: " + problem);
  const int nv = int(input.views.size());
  for (const auto& [a, b] : pairs)
    SATMESH_CHECK(a >= 0 && b >= 0 && a < nv && b < nv && a != b, ErrorCode::kInvalidArgument,
                  "bias: pair " + Num(a) + "-" + Num(b) + " is not a pair of " + Num(nv) + " views");
  SATMESH_CHECK(options.reference_view < nv, ErrorCode::kInvalidArgument,
                "bias: reference_view " + Num(options.reference_view) + " out of range");
  SATMESH_CHECK(!input.initial_mesh.faces.empty(), ErrorCode::kInvalidInput,
                "bias: the initial mesh has no faces");

  BiasEstimate out;
  out.bias_col_row_px.assign(nv, Eigen::Vector2d::Zero());
  out.solved.assign(nv, false);
  out.zncc_before.assign(nv, 0.0);
  out.zncc_after.assign(nv, 0.0);
  out.pairs = pairs;
  if (pairs.empty()) return out;
  out.reference_view = ReferenceView(pairs, nv, options.reference_view);
  out.solved[out.reference_view] = true;

  // Coarse level: reduced until the smallest image has >= 64 px at that level.
  int coarse_level = options.coarse_level;
  for (const auto& v : views) coarse_level = std::min(coarse_level, int(v.pyramid.size()) - 1);
  for (const auto& v : input.views)
    while (coarse_level > 0 && (std::min(v.image.width, v.image.height) >> coarse_level) < 64)
      --coarse_level;

  const RayScene scene(input.initial_mesh);
  Problem pb{input, options, views, {}, scene, FaceNormals(input.initial_mesh), {}, {}, 0};
  SurfaceBox(input.initial_mesh, input.min_z, input.max_z, &pb.box_min, &pb.box_max);
  for (const auto& v : views) {
    pb.rpcs.push_back(v.rpc);
    pb.gsd_m += v.gsd_m / nv;
  }

  // Breadth-first over the pair graph: next, the view with most pairs to solved views.
  for (;;) {
    int view = -1;
    std::vector<int> best_neighbours;
    for (int v = 0; v < nv; ++v) {
      if (out.solved[v]) continue;
      std::vector<int> neighbours;
      for (const auto& [a, b] : pairs) {
        if (int(neighbours.size()) >= options.max_neighbours) break;
        if (a == v && out.solved[b]) neighbours.push_back(b);
        if (b == v && out.solved[a]) neighbours.push_back(a);
      }
      if (neighbours.size() > best_neighbours.size()) view = v, best_neighbours = neighbours;
    }
    if (view < 0) break;
    const Eigen::Vector2d d = SolveView(pb, view, best_neighbours, coarse_level, progress,
                                        &out.zncc_before[view], &out.zncc_after[view]);
    out.bias_col_row_px[view] = d;
    out.solved[view] = true;
    pb.rpcs[view] = pb.rpcs[view].WithBias(pb.rpcs[view].bias() + d);
    spdlog::info("bias: view {} ({}) vs {} view(s): ({:+.3f}, {:+.3f}) px (col, row), ZNCC {:.4f} -> {:.4f}",
                 view, input.views[view].name, best_neighbours.size(), d.x(), d.y(),
                 out.zncc_before[view], out.zncc_after[view]);
  }
  return out;
}

void ApplyViewBiases(const BiasEstimate& estimate, RefineInput* input) {
  for (size_t v = 0; v < input->views.size() && v < estimate.bias_col_row_px.size(); ++v) {
    RpcModel& rpc = input->views[v].rpc;
    rpc = rpc.WithBias(rpc.bias() + estimate.bias_col_row_px[v]);
  }
}

}  // namespace satmesh
