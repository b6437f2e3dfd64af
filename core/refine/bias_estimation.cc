#include "core/refine/bias_estimation.h"

#include <Eigen/LU>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <list>
#include <map>
#include <memory>

#include <omp.h>

#include "core/common/error.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/block_datum.h"
#include "core/refine/pairs.h"
#include "core/mesh/topology.h"
#include "core/refine/photometric_gradient.h"
#include "core/refine/quadratic_step.h"
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
  // With the ray cosines, the warp from this view runs its AVX2 path (warp.h).
  CastHitMap(pb.scene, &out, &pb.normals);
  return out;
}

// The level data of solved views (their RPCs no longer change), kept for the views solved
// after them, least recently used dropped first beyond max_bytes. Without the hit
// records (a neighbour's warp reads its surface points and ray cosines only).
class SolvedLevels {
 public:
  SolvedLevels(const Problem& pb, double max_bytes) : pb_(pb), max_bytes_(max_bytes) {}

  std::shared_ptr<const ViewLevel> Get(int view, int level) {
    const auto key = std::make_pair(view, level);
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->key != key) continue;
      entries_.splice(entries_.begin(), entries_, it);  // most recent first
      return entries_.front().level;
    }
    ViewLevel built = BuildLevel(pb_, view, level);
    built.hit_map.hits = {};
    const size_t pixels = built.image.pixels.size();
    const double bytes = double(pixels) * (sizeof(float) + sizeof(Eigen::Vector3f) +
                                           sizeof(SurfacePoint) + sizeof(float));
    auto shared = std::make_shared<const ViewLevel>(std::move(built));
    entries_.push_front({key, shared, bytes});
    bytes_ += bytes;
    while (bytes_ > max_bytes_ && !entries_.empty()) {
      bytes_ -= entries_.back().bytes;
      entries_.pop_back();  // still alive while an objective holds it
    }
    return shared;
  }

 private:
  struct Entry {
    std::pair<int, int> key;
    std::shared_ptr<const ViewLevel> level;
    double bytes;
  };
  const Problem& pb_;
  double max_bytes_;
  double bytes_ = 0;
  std::list<Entry> entries_;
};

// Mean ZNCC of the solved neighbours warped into `target` shifted by d (full-res px).
// The target's hit map for a shift is its unshifted one moved by the rounded level shift
// (a biased view's pixel q sees what the unbiased one sees at q - d). Shifts are
// evaluated in parallel, one per thread; each thread has its own shifted copy of the
// target (what the warp into it reads: image, projection lattice, surface points).
class ShiftObjective {
 public:
  ShiftObjective(const Problem& pb, int target, const std::vector<int>& neighbours, int level,
                 SolvedLevels* solved)
      : pb_(pb), level_(level), base_rpc_(pb.rpcs[target]),
        photo_(PhotometricOptionsAt(pb.options.refine, pb.gsd_m * std::ldexp(1.0, level))) {
    ViewLevel base = BuildLevel(pb, target, level);
    base_surface_ = std::move(base.hit_map.surface);
    slots_.resize(std::max(1, omp_get_max_threads()));
    for (Slot& s : slots_) {
      s.target.view = base.view;
      s.target.level = level;
      s.target.image = base.image;
      s.target.hit_map.surface.resize(base_surface_.size());
    }
    for (int n : neighbours) neighbours_.push_back(solved->Get(n, level));
  }

  double operator()(const Eigen::Vector2d& d) { return Evaluate({d}).front(); }

  // The objective at each shift (cached: a shift is computed once).
  std::vector<double> Evaluate(const std::vector<Eigen::Vector2d>& shifts) {
    std::vector<Eigen::Vector2d> todo;
    for (const Eigen::Vector2d& d : shifts)
      if (!cache_.count(Key(d)) &&
          std::none_of(todo.begin(), todo.end(), [&](const auto& t) { return Key(t) == Key(d); }))
        todo.push_back(d);
    std::vector<double> values(todo.size());
    if (todo.size() == 1) {
      values[0] = Compute(todo[0], &slots_[0]);  // the warp's rows in parallel
    } else {
#pragma omp parallel for schedule(dynamic, 1)
      for (size_t k = 0; k < todo.size(); ++k)
        values[k] = Compute(todo[k], &slots_[omp_get_thread_num() % slots_.size()]);
    }
    for (size_t k = 0; k < todo.size(); ++k) cache_[Key(todo[k])] = values[k];
    std::vector<double> out;
    for (const Eigen::Vector2d& d : shifts) out.push_back(cache_.at(Key(d)));
    return out;
  }

 private:
  struct Slot {
    ViewLevel target;
    PairWorkspace workspace;
  };
  static std::pair<long, long> Key(const Eigen::Vector2d& d) {
    return {std::lround(d.x() * 1e6), std::lround(d.y() * 1e6)};
  }

  double Compute(const Eigen::Vector2d& d, Slot* slot) const {
    ViewLevel& target = slot->target;
    const double scale = std::ldexp(1.0, -level_);
    target.rpc = base_rpc_.WithBias(base_rpc_.bias() + d).AtLevel(level_);
    target.projection = ProjectionGrid(target.rpc, pb_.input.frame, pb_.box_min, pb_.box_max,
                                       /*spacing_xy_m=*/16.0, /*spacing_z_m=*/8.0);
    ShiftSurface(int(std::lround(d.x() * scale)), int(std::lround(d.y() * scale)),
                 &target.hit_map.surface);
    double sum = 0;
    long windows = 0;
    for (const auto& n : neighbours_) {
      const PairEnergy e =
          AccumulatePairGradient(*n, target, pb_.normals, photo_, nullptr, &slot->workspace);
      sum += e.sum_zncc;
      windows += e.num_windows;
    }
    return windows >= 16 ? sum / double(windows) : -1.0;
  }

  void ShiftSurface(int dx, int dy, std::vector<SurfacePoint>* surface) const {
    const int w = slots_[0].target.width(), h = slots_[0].target.height();
    for (int row = 0; row < h; ++row) {
      SurfacePoint* out = surface->data() + size_t(row) * w;
      const int r = row - dy;
      if (r < 0 || r >= h) {
        std::fill(out, out + w, SurfacePoint{});
        continue;
      }
      const SurfacePoint* in = base_surface_.data() + size_t(r) * w;
      for (int col = 0; col < w; ++col) {
        const int c = col - dx;
        out[col] = c >= 0 && c < w ? in[c] : SurfacePoint{};
      }
    }
  }

  const Problem& pb_;
  int level_;
  RpcModel base_rpc_;
  std::vector<SurfacePoint> base_surface_;
  std::vector<Slot> slots_;
  std::vector<std::shared_ptr<const ViewLevel>> neighbours_;
  PhotometricOptions photo_;
  std::map<std::pair<long, long>, double> cache_;
};

// Coarse grid search, then 3x3 quadratic steps level by level down to full resolution.
Eigen::Vector2d SolveView(const Problem& pb, SolvedLevels* solved, int view,
                          const std::vector<int>& neighbours,
                          int coarse_level, const Progress& progress, double* zncc_before,
                          double* zncc_after) {
  const BiasOptions& o = pb.options;
  Eigen::Vector2d d(0, 0);
  for (int level = coarse_level; level >= 0; --level) {
    progress.ThrowIfCancelled();
    ShiftObjective f(pb, view, neighbours, level, solved);
    if (level == coarse_level) {
      const int n = int(std::floor(o.search_radius_px / o.coarse_step_px));
      std::vector<Eigen::Vector2d> grid;
      for (int j = -n; j <= n; ++j)
        for (int i = -n; i <= n; ++i) grid.push_back(o.coarse_step_px * Eigen::Vector2d(i, j));
      const std::vector<double> values = f.Evaluate(grid);
      double best = -1e30;
      for (size_t k = 0; k < grid.size(); ++k)
        if (values[k] > best) best = values[k], d = grid[k];
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
  if (!(solved_cache_mb >= 0)) return "solved_cache_mb must be >= 0, got " + Num(solved_cache_mb);
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

  SolvedLevels solved(pb, options.solved_cache_mb * double(1 << 20));
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
    const Eigen::Vector2d d = SolveView(pb, &solved, view, best_neighbours, coarse_level, progress,
                                        &out.zncc_before[view], &out.zncc_after[view]);
    out.bias_col_row_px[view] = d;
    out.solved[view] = true;
    pb.rpcs[view] = pb.rpcs[view].WithBias(pb.rpcs[view].bias() + d);
    spdlog::info("bias: view {} ({}) vs {} view(s): ({:+.3f}, {:+.3f}) px (col, row), ZNCC {:.4f} -> {:.4f}",
                 view, input.views[view].name, best_neighbours.size(), d.x(), d.y(),
                 out.zncc_before[view], out.zncc_after[view]);
  }
  // The datum: the input's RPCs (before this estimate) give the Jacobians; the bias
  // barely changes them.
  std::vector<RpcModel> input_rpcs;
  for (const auto& v : views) input_rpcs.push_back(v.rpc);
  const Eigen::Vector3d centre = 0.5 * (pb.box_min + pb.box_max);
  if (options.minimum_norm_datum) {
    MinimumNormDatum(input_rpcs, input.frame, centre, &out);
    spdlog::info("bias: datum of minimum corrections: the block shifted by ({:+.3f}, {:+.3f}) m "
                 "(east, north) from the reference view's", out.datum_shift_m.x(), out.datum_shift_m.y());
  }
  if (options.refine.RegistersToInitial(input.initial_is_mesh)) {
    // The block put on the initial surface: the common shift the images agree best on,
    // over the best pairs of solved views (at most kDatumPairs, for the cost).
    constexpr size_t kDatumPairs = 8;
    std::vector<std::pair<int, int>> datum_pairs;
    for (const auto& [a, b] : pairs)
      if (out.solved[a] && out.solved[b] && datum_pairs.size() < kDatumPairs) datum_pairs.push_back({a, b});
    const std::vector<Eigen::Matrix2d> jacobians = DatumJacobians(input_rpcs, input.frame, centre);
    const Eigen::Vector2d t0 = out.datum_shift_m;
    const DatumProblem problem{views,     pb.rpcs,    input.frame,   scene,   pb.normals,
                               pb.box_min, pb.box_max, options.refine, pb.gsd_m};
    const SurfaceDatumResult found =
        SurfaceDatum(problem, jacobians, datum_pairs, t0, coarse_level, progress);
    const double before = found.zncc_before, after = found.zncc_after;
    Eigen::Vector2d t = found.t;
    // Where the surface has too little relief to tell (a plane: the objective is flat but
    // for its noise), minimum corrections stay.
    constexpr double kDatumMargin = 0.002;
    const bool observed = after > before + kDatumMargin;
    if (!observed) t = t0;
    for (int v = 0; v < nv; ++v)
      if (out.solved[v]) out.bias_col_row_px[v] += jacobians[v] * (t - t0);
    out.datum_shift_m = t;
    spdlog::info("bias: datum on the initial surface: {} ({:+.3f}, {:+.3f}) m (east, north) from "
                 "the reference view's; mean ZNCC of {} pairs {:.4f} -> {:.4f}{}",
                 observed ? "the block shifted by" : "minimum corrections kept at", t.x(), t.y(),
                 datum_pairs.size(), before, after,
                 observed ? "" : fmt::format(" (not above {:.3f})", before + kDatumMargin));
  }
  return out;
}

void MinimumNormDatum(const std::vector<RpcModel>& rpcs, const LocalFrame& frame,
                      const Eigen::Vector3d& center, BiasEstimate* estimate) {
  const std::vector<Eigen::Matrix2d> jacobians = DatumJacobians(rpcs, frame, center);
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  for (size_t v = 0; v < rpcs.size(); ++v) {
    if (!estimate->solved[v]) continue;
    normal += jacobians[v].transpose() * jacobians[v];
    rhs += jacobians[v].transpose() * estimate->bias_col_row_px[v];
  }
  if (!(std::abs(normal.determinant()) > 1e-12)) return;
  const Eigen::Vector2d t = -normal.inverse() * rhs;
  for (size_t v = 0; v < rpcs.size(); ++v)
    if (estimate->solved[v]) estimate->bias_col_row_px[v] += jacobians[v] * t;
  estimate->datum_shift_m = t;
}

void ApplyViewBiases(const BiasEstimate& estimate, RefineInput* input) {
  for (size_t v = 0; v < input->views.size() && v < estimate.bias_col_row_px.size(); ++v) {
    RpcModel& rpc = input->views[v].rpc;
    rpc = rpc.WithBias(rpc.bias() + estimate.bias_col_row_px[v]);
  }
}

}  // namespace satmesh
