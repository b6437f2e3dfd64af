#include "core/synth/view_plan.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <tuple>

#include "core/common/error.h"
#include "core/refine/pairs.h"

namespace satmesh::synth {
namespace {
constexpr double kDeg = M_PI / 180.0;
constexpr double kEarthR = 6371e3, kAltitude = 600e3;

// Lexicographic: separation violations, partner deficit, pairs short of the target.
using Score = std::tuple<int, int, int>;

// Off-nadir: free, or view i in stratum rank[i] of [min, max] at fraction frac[i] of it.
// Azimuth: stratum i of the spread, offset by jitter[i] in [-0.5, 0.5] of a stratum.
struct State {
  std::vector<double> off_nadir, frac, jitter;
  std::vector<int> rank;
};

class Planner {
 public:
  Planner(const ViewPlanOptions& o, uint64_t seed) : o_(o), gen_(seed * 0x9E3779B97F4A7C15ull + 17) {
    need_ = std::min({o.min_partners, o.num_views - 1, o.max_pairs_per_image});
    target_ = std::min(o.target_pairs, o.num_views * std::min(o.num_views - 1, o.max_pairs_per_image) / 2);
    pair_options_.min_angle_deg = o.min_pair_angle_deg + o.window_margin_deg;
    pair_options_.max_angle_deg = o.max_pair_angle_deg - o.window_margin_deg;
    pair_options_.max_pairs_per_image = o.max_pairs_per_image;
    pair_options_.min_contrast = 0;
    pair_options_.optimal_angle_deg = pair_options_.min_angle_deg;
    pair_options_.partners_per_view = o.max_pairs_per_image;
    pair_options_.max_pairs = o.num_views * o.max_pairs_per_image;
    azimuth0_ = 360 * U();
  }

  double U() { return std::uniform_real_distribution<double>(0, 1)(gen_); }

  Eigen::Vector2d Direction(const State& s, int i) const {
    const double stratum = o_.azimuth_spread_deg / o_.num_views;
    double az = azimuth0_ + (i + 0.5 + o_.azimuth_jitter * s.jitter[i]) * stratum;
    az = std::fmod(az, 360.0);
    return {s.off_nadir[i], az < 0 ? az + 360 : az};
  }

  Score Evaluate(const State& s, std::vector<std::pair<int, int>>* pairs) const {
    std::vector<PairCandidateView> views(s.off_nadir.size());
    for (int i = 0; i < int(views.size()); ++i) {
      views[i].direction = SatelliteDirection(Direction(s, i));
      views[i].contrast = 1;
    }
    int too_close = 0;
    for (size_t i = 0; i < views.size(); ++i)
      for (size_t j = i + 1; j < views.size(); ++j)
        too_close += IntersectionAngleDeg(views[i].direction, views[j].direction) < o_.min_separation_deg;
    *pairs = SelectPairs(views, Eigen::AlignedBox2d(), pair_options_).IndexPairs();
    std::vector<int> count(views.size(), 0);
    for (const auto& [a, b] : *pairs) ++count[a], ++count[b];
    int deficit = 0;
    for (int c : count) deficit += std::max(0, need_ - c);
    return {too_close, deficit, std::max(0, target_ - int(pairs->size()))};
  }

  // Random start, then local search: one view's off-nadir or azimuth jitter per step
  // (or two views swap off-nadir strata), accepting moves that are no worse: a random
  // walk on the feasible plateau keeps the directions spread.
  std::optional<ViewPlan> Run() {
    const int n = o_.num_views;
    State s;
    for (int i = 0; i < n; ++i) {
      s.frac.push_back(U());
      s.jitter.push_back(U() - 0.5);
      s.rank.push_back(i);
      s.off_nadir.push_back(0);
    }
    std::shuffle(s.rank.begin(), s.rank.end(), gen_);
    for (int i = 0; i < n; ++i) SetOffNadir(&s, i);
    std::vector<std::pair<int, int>> pairs;
    Score score = Evaluate(s, &pairs);
    for (int it = 0; it < o_.iterations && score != Score{0, 0, 0}; ++it) Step(&s, &score, &pairs);
    for (int it = 0; it < o_.iterations / 4 && score == Score{0, 0, 0}; ++it) Step(&s, &score, &pairs);
    if (score != Score{0, 0, 0}) return std::nullopt;
    ViewPlan plan;
    for (int i = 0; i < o_.num_views; ++i) plan.off_nadir_azimuth_deg.push_back(Direction(s, i));
    plan.pairs = std::move(pairs);
    for (int i = 0; i < o_.num_views; ++i)
      for (int j = i + 1; j < o_.num_views; ++j) {
        const double a = ViewIntersectionAngleDeg(plan.off_nadir_azimuth_deg[i], plan.off_nadir_azimuth_deg[j]);
        plan.candidate_pairs += a >= o_.min_pair_angle_deg && a <= o_.max_pair_angle_deg;
      }
    return plan;
  }

  void SetOffNadir(State* s, int i) const {
    const double lo = o_.min_off_nadir_deg, hi = o_.max_off_nadir_deg;
    const double stratum = (hi - lo) / o_.num_views, w = o_.off_nadir_stratum_width;
    double v = w > 0 ? lo + (s->rank[i] + 0.5 + w * (s->frac[i] - 0.5)) * stratum
                     : lo + s->frac[i] * (hi - lo);
    if (v < lo) v = 2 * lo - v;  // reflect: strata at the ends stay as dense as the rest
    if (v > hi) v = 2 * hi - v;
    s->off_nadir[i] = std::clamp(v, lo, hi);
  }

  void Step(State* s, Score* score, std::vector<std::pair<int, int>>* pairs) {
    const int n = o_.num_views;
    State t = *s;
    const int i = int(U() * n) % n, j = int(U() * n) % n;
    const double r = U();
    if (r < 0.35) {
      std::swap(t.rank[i], t.rank[j]);
      SetOffNadir(&t, j);
    } else if (r < 0.7) {
      t.frac[i] = U();
    } else {
      t.jitter[i] = U() - 0.5;
    }
    SetOffNadir(&t, i);
    std::vector<std::pair<int, int>> p;
    const Score ts = Evaluate(t, &p);
    if (ts <= *score) *s = std::move(t), *score = ts, *pairs = std::move(p);
  }

 private:
  const ViewPlanOptions& o_;
  std::mt19937_64 gen_;
  int need_ = 1, target_ = 0;
  PairOptions pair_options_;
  double azimuth0_ = 0;
};

}  // namespace

std::string ViewPlanOptions::Check() const {
  if (num_views < 2 || num_views > 64) return "num_views must be in [2, 64]";
  if (!(min_off_nadir_deg >= 0 && max_off_nadir_deg <= 45 && min_off_nadir_deg < max_off_nadir_deg))
    return "need 0 <= min_off_nadir_deg < max_off_nadir_deg <= 45";
  if (!(azimuth_spread_deg > 0 && azimuth_spread_deg <= 360)) return "azimuth_spread_deg must be in (0, 360]";
  if (!(azimuth_jitter >= 0 && azimuth_jitter <= 1)) return "azimuth_jitter must be in [0, 1]";
  if (!(window_margin_deg >= 0)) return "window_margin_deg must be >= 0";
  if (!(min_pair_angle_deg > 0 &&
        min_pair_angle_deg + 2 * window_margin_deg < max_pair_angle_deg))
    return "need 0 < min_pair_angle_deg + 2 * window_margin_deg < max_pair_angle_deg";
  if (max_pairs_per_image < 1) return "max_pairs_per_image must be >= 1";
  if (min_partners < 1) return "min_partners must be >= 1";
  if (target_pairs < 0) return "target_pairs must be >= 0";
  if (!(min_separation_deg >= 0)) return "min_separation_deg must be >= 0";
  if (iterations < 1) return "iterations must be >= 1";
  if (!(off_nadir_stratum_width >= 0)) return "off_nadir_stratum_width must be >= 0";
  return "";
}

Eigen::Vector3d SatelliteDirection(const Eigen::Vector2d& off_nadir_azimuth) {
  const double zen = std::asin(std::min(1.0, (kEarthR + kAltitude) / kEarthR *
                                                 std::sin(off_nadir_azimuth.x() * kDeg)));
  const double az = off_nadir_azimuth.y() * kDeg;
  return {std::sin(zen) * std::sin(az), std::sin(zen) * std::cos(az), std::cos(zen)};
}

double ViewIntersectionAngleDeg(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::acos(std::clamp(SatelliteDirection(a).dot(SatelliteDirection(b)), -1.0, 1.0)) / kDeg;
}

ViewPlan PlanViewSet(const ViewPlanOptions& o, uint64_t seed) {
  const std::string why = o.Check();
  SATMESH_CHECK(why.empty(), ErrorCode::kInvalidArgument, "ViewPlanOptions: " + why);
  for (int restart = 0; restart < 20; ++restart) {
    Planner planner(o, seed * 131 + restart);
    if (auto plan = planner.Run()) return *plan;
  }
  ThrowError(ErrorCode::kInvalidArgument,
             "PlanViews: no set of " + std::to_string(o.num_views) + " views over " +
                 std::to_string(o.azimuth_spread_deg) + " deg of azimuth gives every view " +
                 std::to_string(o.min_partners) + " stereo partners");
}

}  // namespace satmesh::synth
