#include "core/eval/mesh_metrics.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/common/error.h"
#include "core/common/stats.h"
#include "core/raycast/ray_scene.h"

namespace satmesh {
namespace {

bool InCrop(const Eigen::Vector3d& p, const Mesh3dOptions& o) {
  if (!(o.crop_xmin < o.crop_xmax)) return true;
  return p.x() >= o.crop_xmin && p.x() <= o.crop_xmax && p.y() >= o.crop_ymin &&
         p.y() <= o.crop_ymax;
}

// Samples in the crop, and which of them are facade samples.
SurfaceSamples CroppedSamples(const TriangleMesh& mesh, const Mesh3dOptions& o,
                              std::vector<uint8_t>& is_facade) {
  SurfaceSamples s = SampleSurface(mesh, o.sampling);
  SurfaceSamples kept;
  is_facade.clear();
  for (size_t k = 0; k < s.points.size(); ++k) {
    if (!InCrop(s.points[k], o)) continue;
    kept.points.push_back(s.points[k]);
    kept.normals.push_back(s.normals[k]);
    is_facade.push_back(IsFacadeNormal(s.normals[k], o.facade_max_abs_nz) ? 1 : 0);
  }
  return kept;
}

// Fraction of distances below each threshold, over the selected samples.
std::vector<double> FractionsWithin(const std::vector<float>& d, const std::vector<uint8_t>& select,
                                    const std::vector<double>& thresholds, size_t& count) {
  std::vector<double> f(thresholds.size(), 0.0);
  count = 0;
  for (size_t k = 0; k < d.size(); ++k) {
    if (!select.empty() && !select[k]) continue;
    ++count;
    for (size_t t = 0; t < thresholds.size(); ++t)
      if (d[k] < thresholds[t]) f[t] += 1;
  }
  if (count > 0)
    for (double& v : f) v /= double(count);
  return f;
}

Mesh3dScores Scores(const std::vector<float>& d_result, const std::vector<uint8_t>& sel_result,
                    const std::vector<float>& d_truth, const std::vector<uint8_t>& sel_truth,
                    const std::vector<double>& thresholds) {
  Mesh3dScores s;
  s.thresholds_m = thresholds;
  s.accuracy = FractionsWithin(d_result, sel_result, thresholds, s.num_result_samples);
  s.completeness = FractionsWithin(d_truth, sel_truth, thresholds, s.num_truth_samples);
  for (size_t t = 0; t < thresholds.size(); ++t) {
    const double p = s.accuracy[t], r = s.completeness[t];
    s.fscore.push_back(p + r > 0 ? 2 * p * r / (p + r) : 0.0);
  }
  return s;
}

}  // namespace

std::string SampleOptions::Check() const {
  if (!(samples_per_m2 > 0 && samples_per_m2 <= 1e4))
    return "samples_per_m2 must be in (0, 1e4], got " + std::to_string(samples_per_m2);
  return "";
}

std::string Mesh3dOptions::Check() const {
  if (auto m = sampling.Check(); !m.empty()) return "sampling: " + m;
  if (thresholds_m.empty()) return "thresholds_m must not be empty";
  for (double t : thresholds_m)
    if (!(t > 0)) return "thresholds_m must be > 0, got " + std::to_string(t);
  if (!(facade_max_abs_nz > 0 && facade_max_abs_nz <= 1))
    return "facade_max_abs_nz must be in (0, 1], got " + std::to_string(facade_max_abs_nz);
  return "";
}

SurfaceSamples SampleSurface(const TriangleMesh& mesh, const SampleOptions& options) {
  const std::string msg = options.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, "SampleOptions: " + msg);
  ValidateMesh(mesh, "SampleSurface mesh");
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<float> uni(0.f, 1.f);
  SurfaceSamples s;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3f &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]],
                          &c = mesh.vertices[f[2]];
    const Eigen::Vector3f cross = (b - a).cross(c - a);
    const double area = 0.5 * double(cross.norm());
    const int n = int(std::floor(area * options.samples_per_m2 + uni(rng)));
    if (n <= 0 || !(area > 0)) continue;
    const Eigen::Vector3f normal = cross.normalized();
    for (int k = 0; k < n; ++k) {
      const float r1 = std::sqrt(uni(rng)), r2 = uni(rng);  // uniform on the triangle
      const Eigen::Vector3f p = (1 - r1) * a + r1 * (1 - r2) * b + r1 * r2 * c;
      s.points.push_back(mesh.origin + p.cast<double>());
      s.normals.push_back(normal);
    }
  }
  return s;
}

namespace {

// UnderOverhang, SeenByViews and MeasureFacadeOffsets over a scene of `mesh` the caller
// built (EvaluateMesh3d builds one per surface for all three).

std::vector<uint8_t> UnderOverhangIn(const TriangleMesh& mesh, const RayScene& scene,
                                     const SurfaceSamples& samples) {
  std::vector<uint8_t> covered(samples.points.size(), 0);
  if (samples.points.empty() || mesh.faces.empty()) return covered;
  std::vector<Ray> rays(samples.points.size());
  for (size_t k = 0; k < rays.size(); ++k) {
    rays[k].origin = (samples.points[k] - mesh.origin).cast<float>() + 0.1f * samples.normals[k];
    rays[k].direction = Eigen::Vector3f::UnitZ();
  }
  scene.Occluded(rays.data(), covered.data(), rays.size());
  return covered;
}

std::vector<uint8_t> SeenByViewsIn(const TriangleMesh& mesh, const RayScene& scene,
                                   const SurfaceSamples& samples, const ViewDirections& directions,
                                   int min_views, double min_cos) {
  const size_t n = samples.points.size();
  std::vector<uint8_t> seen(n, 0);
  if (n == 0 || mesh.faces.empty()) return seen;
  std::vector<uint8_t> count(n, 0);
  std::vector<Ray> rays;
  std::vector<size_t> index;
  std::vector<uint8_t> occluded;
  for (const auto& to_sensor : directions) {
    SATMESH_CHECK(to_sensor.size() == n, ErrorCode::kInvalidArgument,
                  "SeenByViews: a view has " + std::to_string(to_sensor.size()) +
                      " directions for " + std::to_string(n) + " samples");
    rays.clear();
    index.clear();
    for (size_t k = 0; k < n; ++k) {
      const Eigen::Vector3f& d = to_sensor[k];
      if (d.isZero() || double(samples.normals[k].dot(d)) < min_cos) continue;
      Ray r;
      r.origin = (samples.points[k] - mesh.origin).cast<float>() + 0.05f * samples.normals[k];
      r.direction = d;
      rays.push_back(r);
      index.push_back(k);
    }
    occluded.assign(rays.size(), 0);
    if (!rays.empty()) scene.Occluded(rays.data(), occluded.data(), rays.size());
    for (size_t i = 0; i < rays.size(); ++i)
      if (!occluded[i]) ++count[index[i]];
  }
  for (size_t k = 0; k < n; ++k) seen[k] = count[k] >= min_views;
  return seen;
}

FacadeOffsets FacadeOffsetsIn(const TriangleMesh& result, const RayScene& scene,
                              const SurfaceSamples& samples, const std::vector<uint8_t>& is_facade,
                              double max_offset_m) {
  SATMESH_CHECK(is_facade.size() == samples.points.size(), ErrorCode::kInvalidArgument,
                "MeasureFacadeOffsets: " + std::to_string(is_facade.size()) + " flags for " +
                    std::to_string(samples.points.size()) + " samples");
  SATMESH_CHECK(max_offset_m > 0, ErrorCode::kInvalidArgument,
                "MeasureFacadeOffsets: max_offset_m must be > 0, got " +
                    std::to_string(max_offset_m));
  FacadeOffsets f;
  f.max_offset_m = max_offset_m;
  std::vector<Ray> rays;  // per facade sample: outward, then inward
  for (size_t k = 0; k < samples.points.size(); ++k) {
    if (!is_facade[k]) continue;
    const Eigen::Vector3f p = (samples.points[k] - result.origin).cast<float>();
    for (const float sign : {1.f, -1.f})
      rays.push_back({p, sign * samples.normals[k], 0.f, float(max_offset_m)});
  }
  f.num_samples = rays.size() / 2;
  if (rays.empty() || result.faces.empty()) return f;
  std::vector<RayHit> hits(rays.size());
  scene.Intersect(rays.data(), hits.data(), rays.size());
  std::vector<double> offsets;
  for (size_t i = 0; i < f.num_samples; ++i) {
    const RayHit &out = hits[2 * i], &in = hits[2 * i + 1];
    if (!out.hit() && !in.hit()) continue;
    const bool outside = out.hit() && (!in.hit() || out.t <= in.t);
    offsets.push_back(outside ? double(out.t) : -double(in.t));
  }
  f.num_crossed = offsets.size();
  for (const double o : offsets) {
    f.outside_fraction += o > kFacadeOffsetFarM;
    f.inside_fraction += o < -kFacadeOffsetFarM;
  }
  f.outside_fraction /= double(f.num_samples);
  f.inside_fraction /= double(f.num_samples);
  f.p25_m = Quantile(offsets, 0.25);
  f.median_m = Quantile(offsets, 0.5);
  f.p75_m = Quantile(offsets, 0.75);
  return f;
}

}  // namespace

std::vector<uint8_t> UnderOverhang(const TriangleMesh& mesh, const SurfaceSamples& samples) {
  return UnderOverhangIn(mesh, RayScene(mesh), samples);
}

std::vector<uint8_t> SeenByViews(const TriangleMesh& mesh, const SurfaceSamples& samples,
                                 const ViewDirections& directions, int min_views, double min_cos) {
  return SeenByViewsIn(mesh, RayScene(mesh), samples, directions, min_views, min_cos);
}

FacadeOffsets MeasureFacadeOffsets(const TriangleMesh& result, const SurfaceSamples& samples,
                                   const std::vector<uint8_t>& is_facade, double max_offset_m) {
  return FacadeOffsetsIn(result, RayScene(result), samples, is_facade, max_offset_m);
}

namespace {

// The facade samples at least two views see on their own surface: the metric's selection.
std::vector<uint8_t> SeenFacade(const TriangleMesh& mesh, const RayScene& scene,
                                const SurfaceSamples& samples, const std::vector<uint8_t>& is_facade,
                                const ViewDirectionsFn& views) {
  SurfaceSamples facade;
  std::vector<size_t> index;
  for (size_t k = 0; k < samples.points.size(); ++k)
    if (is_facade[k]) {
      facade.points.push_back(samples.points[k]);
      facade.normals.push_back(samples.normals[k]);
      index.push_back(k);
    }
  std::vector<uint8_t> selected(samples.points.size(), 0);
  if (index.empty()) return selected;
  const std::vector<uint8_t> seen =
      SeenByViewsIn(mesh, scene, facade, views(facade.points), kSeenMinViews, kSeenMinCos);
  for (size_t i = 0; i < index.size(); ++i) selected[index[i]] = seen[i];
  return selected;
}

}  // namespace

Mesh3dMetrics EvaluateMesh3d(const TriangleMesh& result, const TriangleMesh& truth,
                             const Mesh3dOptions& options, const ViewDirectionsFn* views) {
  const std::string msg = options.Check();
  SATMESH_CHECK(msg.empty(), ErrorCode::kInvalidArgument, "Mesh3dOptions: " + msg);
  std::vector<uint8_t> facade_result, facade_truth;
  const SurfaceSamples s_result = CroppedSamples(result, options, facade_result);
  const SurfaceSamples s_truth = CroppedSamples(truth, options, facade_truth);
  const double max_d = *std::max_element(options.thresholds_m.begin(), options.thresholds_m.end());
  const std::vector<float> d_result =
      SurfaceDistance(truth, options.backend).Distances(s_result.points, max_d);
  const std::vector<float> d_truth =
      SurfaceDistance(result, options.backend).Distances(s_truth.points, max_d);
  // One ray scene per surface for the overhangs, the offsets and the views.
  const RayScene result_scene(result), truth_scene(truth);
  Mesh3dMetrics m;
  m.all = Scores(d_result, {}, d_truth, {}, options.thresholds_m);
  m.facade = Scores(d_result, facade_result, d_truth, facade_truth, options.thresholds_m);
  m.under_overhang = Scores(d_result, UnderOverhangIn(result, result_scene, s_result), d_truth,
                            UnderOverhangIn(truth, truth_scene, s_truth), options.thresholds_m);
  m.facade_offset =
      FacadeOffsetsIn(result, result_scene, s_truth, facade_truth, kFacadeOffsetMaxM);
  if (views && *views) {
    m.seen_facade = Scores(d_result, SeenFacade(result, result_scene, s_result, facade_result, *views),
                           d_truth, SeenFacade(truth, truth_scene, s_truth, facade_truth, *views),
                           options.thresholds_m);
  }
  return m;
}

}  // namespace satmesh
