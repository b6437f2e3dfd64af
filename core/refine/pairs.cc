#include "core/refine/pairs.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <sstream>

namespace satmesh {
namespace {

constexpr double kDeg = M_PI / 180.0;

bool Known(double v) { return std::isfinite(v); }

// Unit vector towards the sun (x east, y north, z up).
Eigen::Vector3d SunDirection(double elevation_deg, double azimuth_deg) {
  const double e = elevation_deg * kDeg, a = azimuth_deg * kDeg;
  return {std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e)};
}

// Union-find over views, for the spanning forest.
struct Components {
  explicit Components(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int Find(int v) { return parent[v] == v ? v : parent[v] = Find(parent[v]); }
  bool Join(int a, int b) {
    a = Find(a), b = Find(b);
    if (a == b) return false;
    parent[a] = b;
    return true;
  }
  std::vector<int> parent;
};

// Number of pairs the selection aims for: the user's cap, else 1.5 per view (at least 10
// where that many candidates exist): what keeps a 26-view tile near the cost of the
// pairs a 5-13 degree rule found there (docs/benchmarks-history.md, session 9).
int PairBudget(int num_usable, const PairOptions& o) {
  if (o.max_pairs > 0) return o.max_pairs;
  return std::max(10, int(std::ceil(1.5 * num_usable)));
}

std::string Refusal(const std::vector<PairCandidateView>& views, const std::vector<int>& usable,
                    const Eigen::AlignedBox2d& surface, const PairOptions& o) {
  std::ostringstream why;
  if (usable.size() < 2) {
    why << "fewer than 2 views with contrast >= " << o.min_contrast << " (" << usable.size()
        << " of " << views.size() << ")";
    return why.str();
  }
  // The pair closest to being accepted, and what stops it.
  double best_overlap = -1, narrowest = 1e9, widest = 0;
  int oi = -1, oj = -1;
  for (size_t a = 0; a < usable.size(); ++a)
    for (size_t b = a + 1; b < usable.size(); ++b) {
      const int i = usable[a], j = usable[b];
      const double ov = FootprintOverlap(views[i].footprint, views[j].footprint, surface);
      const double angle = IntersectionAngleDeg(views[i].direction, views[j].direction);
      if (ov > best_overlap) best_overlap = ov, oi = i, oj = j;
      if (ov >= o.min_overlap) narrowest = std::min(narrowest, angle), widest = std::max(widest, angle);
    }
  if (best_overlap < o.min_overlap) {
    why << "the views do not overlap on the surface: the best pair (" << oi << ", " << oj
        << ") shares " << std::lround(100 * best_overlap) << "% of it (min_pair_overlap "
        << o.min_overlap << ")";
  } else if (narrowest < o.min_angle_deg && widest < o.min_angle_deg) {
    why << "the overlapping views converge by at most " << widest
        << " degrees, under min_pair_angle_deg " << o.min_angle_deg
        << " (the height is not constrained)";
  } else {
    why << "no overlapping pair converges within [" << o.min_angle_deg << ", "
        << o.max_angle_deg << "] degrees (narrowest " << narrowest << ", widest " << widest << ")";
  }
  return why.str();
}

// Facade directions whose coverage the selection tracks: outward normals every 45 degrees.
constexpr int kFacadeDirections = 8;

// A pair covers a facade direction when both of its views see such facades: the lesser of
// the two views' FacadeVisibility.
std::array<double, kFacadeDirections> PairFacadeCoverage(const PairCandidateView& a,
                                                         const PairCandidateView& b) {
  std::array<double, kFacadeDirections> c{};
  for (int d = 0; d < kFacadeDirections; ++d) {
    const double azimuth = d * 360.0 / kFacadeDirections;
    c[d] = std::min(FacadeVisibility(a, azimuth), FacadeVisibility(b, azimuth));
  }
  return c;
}

// Coverage per facade direction at which a direction counts as covered: about one pair
// of views 25 degrees off nadir facing it (sin 25° = 0.42).
constexpr double kFacadeCoverageTarget = 0.4;

// Facade directions a pair adds to the selection's coverage, in [0, kFacadeDirections]:
// how much of each direction's shortfall to kFacadeCoverageTarget it fills.
double FacadeGain(const std::array<double, kFacadeDirections>& pair,
                  const std::array<double, kFacadeDirections>& covered) {
  double gain = 0;
  for (int d = 0; d < kFacadeDirections; ++d)
    gain += (std::min(kFacadeCoverageTarget, covered[d] + pair[d]) -
             std::min(kFacadeCoverageTarget, covered[d])) /
            kFacadeCoverageTarget;
  return gain;
}

}  // namespace

double FacadeVisibility(const PairCandidateView& view, double facade_azimuth_deg) {
  const Eigen::Vector3d outward(std::sin(facade_azimuth_deg * kDeg),
                                std::cos(facade_azimuth_deg * kDeg), 0);
  return std::max(0.0, -view.direction.normalized().dot(outward));
}

std::vector<std::pair<int, int>> PairSelection::IndexPairs() const {
  std::vector<std::pair<int, int>> out;
  for (const auto& p : pairs) out.emplace_back(p.i, p.j);
  return out;
}

std::vector<std::pair<int, int>> PairSelection::IndexPairsBestFirst() const {
  std::vector<StereoPair> by_score = pairs;
  std::stable_sort(by_score.begin(), by_score.end(),
                   [](const StereoPair& a, const StereoPair& b) { return a.score > b.score; });
  std::vector<std::pair<int, int>> out;
  for (const auto& p : by_score) out.emplace_back(p.i, p.j);
  return out;
}

double IntersectionAngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0);
  return std::acos(c) / kDeg;
}

double FootprintOverlap(const Eigen::AlignedBox2d& a, const Eigen::AlignedBox2d& b,
                        const Eigen::AlignedBox2d& surface) {
  if (surface.isEmpty() || surface.volume() <= 0) return 1.0;
  Eigen::AlignedBox2d both = surface;
  if (!a.isEmpty()) both = both.intersection(a);
  if (!b.isEmpty()) both = both.intersection(b);
  return both.isEmpty() ? 0.0 : both.volume() / surface.volume();
}

double PairScore(const PairCandidateView& a, const PairCandidateView& b, double angle_deg,
                 double overlap, const PairOptions& o) {
  const double precision = std::min(1.0, angle_deg / o.optimal_angle_deg);
  const double occlusion =
      angle_deg <= o.optimal_angle_deg
          ? 1.0
          : 1.0 - 0.5 * std::min(1.0, (angle_deg - o.optimal_angle_deg) /
                                          std::max(1e-9, o.max_angle_deg - o.optimal_angle_deg));
  double sun = 1.0;
  if (Known(a.sun_elevation_deg) && Known(a.sun_azimuth_deg) && Known(b.sun_elevation_deg) &&
      Known(b.sun_azimuth_deg)) {
    const double d = IntersectionAngleDeg(SunDirection(a.sun_elevation_deg, a.sun_azimuth_deg),
                                          SunDirection(b.sun_elevation_deg, b.sun_azimuth_deg));
    sun = 0.25 + 0.75 * std::exp(-(d / 25.0) * (d / 25.0));
  }
  double date = 1.0;
  if (Known(a.time_s) && Known(b.time_s)) {
    const double days = std::abs(a.time_s - b.time_s) / 86400.0;
    date = 0.5 + 0.5 * std::exp(-days / 180.0);
  }
  return precision * occlusion * std::clamp(overlap, 0.0, 1.0) * sun * date;
}

PairSelection SelectPairs(const std::vector<PairCandidateView>& views,
                          const Eigen::AlignedBox2d& surface, const PairOptions& o) {
  PairSelection out;
  const int n = int(views.size());
  std::vector<int> usable;
  for (int v = 0; v < n; ++v)
    if (views[v].contrast >= o.min_contrast) usable.push_back(v);

  std::vector<StereoPair> candidates;
  for (size_t a = 0; a < usable.size(); ++a)
    for (size_t b = a + 1; b < usable.size(); ++b) {
      const int i = usable[a], j = usable[b];
      StereoPair p{i, j, IntersectionAngleDeg(views[i].direction, views[j].direction), 0, 0};
      if (p.angle_deg < o.min_angle_deg || p.angle_deg > o.max_angle_deg) continue;
      p.overlap = FootprintOverlap(views[i].footprint, views[j].footprint, surface);
      if (p.overlap < o.min_overlap) continue;
      p.score = PairScore(views[i], views[j], p.angle_deg, p.overlap, o);
      candidates.push_back(p);
    }
  out.num_candidates = int(candidates.size());
  if (candidates.empty()) {
    out.refusal = Refusal(views, usable, surface, o);
    return out;
  }
  // Best first; ties by index, so that the selection is deterministic.
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const StereoPair& x, const StereoPair& y) { return x.score > y.score; });

  std::vector<bool> taken(candidates.size(), false);
  std::vector<int> count(n, 0);
  std::vector<std::array<double, kFacadeDirections>> facades;
  for (const StereoPair& p : candidates) facades.push_back(PairFacadeCoverage(views[p.i], views[p.j]));
  std::array<double, kFacadeDirections> covered{};
  auto take = [&](size_t k) {
    taken[k] = true;
    ++count[candidates[k].i], ++count[candidates[k].j];
    for (int d = 0; d < kFacadeDirections; ++d) covered[d] += facades[k][d];
    out.pairs.push_back(candidates[k]);
  };
  // What a free candidate adds now: its score, raised by the facade directions it covers
  // that the selection does not yet (walls are seen only by views on their side).
  auto value = [&](size_t k) { return candidates[k].score * (1.0 + FacadeGain(facades[k], covered)); };
  // 1. Maximum spanning forest: every view with a candidate gets a partner, and the
  //    views that can be linked are linked (one bias reference reaches them all).
  Components components(n);
  for (size_t k = 0; k < candidates.size(); ++k)
    if (components.Join(candidates[k].i, candidates[k].j)) take(k);
  // The free candidate of highest value within the cap per image (of view v if v >= 0).
  auto best_free = [&](int v) {
    long best = -1;
    for (size_t c = 0; c < candidates.size(); ++c) {
      const StereoPair& p = candidates[c];
      if (taken[c] || (v >= 0 && p.i != v && p.j != v)) continue;
      if (count[p.i] >= o.max_pairs_per_image || count[p.j] >= o.max_pairs_per_image) continue;
      if (best < 0 || value(c) > value(size_t(best))) best = long(c);
    }
    return best;
  };
  // 2. Partners: rounds in which each view short of k partners takes its best free pair.
  const int budget = std::max(PairBudget(int(usable.size()), o), int(out.pairs.size()));
  for (int k = 2; k <= o.partners_per_view; ++k)
    for (int v : usable) {
      if (count[v] >= k || int(out.pairs.size()) >= budget) continue;
      if (const long c = best_free(v); c >= 0) take(size_t(c));
    }
  // 3. The budget: the most valuable remaining pairs within the cap per image.
  while (int(out.pairs.size()) < budget) {
    const long c = best_free(-1);
    if (c < 0) break;
    take(size_t(c));
  }
  for (int v : usable)
    if (count[v] == 0) out.unpaired_views.push_back(v);
  std::sort(out.pairs.begin(), out.pairs.end(), [](const StereoPair& x, const StereoPair& y) {
    return std::make_pair(x.i, x.j) < std::make_pair(y.i, y.j);
  });
  return out;
}

}  // namespace satmesh
