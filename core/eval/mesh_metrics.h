#pragma once
// 3D metrics of a result mesh against a ground-truth mesh (needs 3D truth, i.e.
// synthetic scenes): surfaces sampled uniformly by area; accuracy = fraction of result
// samples within t of the truth surface, completeness = fraction of truth samples within
// t of the result surface, F-score = harmonic mean; all samples and facades only.
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/eval/surface_distance.h"
#include "core/mesh/mesh.h"

namespace satmesh {

struct SurfaceSamples {
  std::vector<Eigen::Vector3d> points;   // absolute, in the mesh's CRS
  std::vector<Eigen::Vector3f> normals;  // unit normal of the sampled face
};

struct SampleOptions {
  double samples_per_m2 = 4.0;  // expected samples per square metre, in (0, 1e4]
  uint32_t seed = 1;            // random generator seed (sampling is deterministic)
  std::string Check() const;
};

// Uniform random samples by area: each face gets floor(area * density + u) samples,
// u ~ U[0, 1), at uniform barycentric positions.
SurfaceSamples SampleSurface(const TriangleMesh& mesh, const SampleOptions& options = {});

// A facade sample has a near-horizontal normal: |n_z| < max_abs_nz.
inline bool IsFacadeNormal(const Eigen::Vector3f& n, double max_abs_nz) {
  return std::abs(double(n.z())) < max_abs_nz;
}

struct Mesh3dOptions {
  SampleOptions sampling;                         // on both surfaces
  std::vector<double> thresholds_m{0.3, 0.5, 1.0};  // distance thresholds, each > 0
  double facade_max_abs_nz = 0.3;                 // facade: |n_z| below, in (0, 1]
  // XY crop (absolute, mesh CRS): samples outside are not counted; unused if xmin >= xmax.
  double crop_xmin = 0, crop_ymin = 0, crop_xmax = 0, crop_ymax = 0;
  DistanceBackend backend = DistanceBackend::kEmbree;  // point-to-surface distances
  std::string Check() const;
};

struct Mesh3dScores {
  std::vector<double> thresholds_m;
  std::vector<double> accuracy;      // per threshold, fraction in [0, 1]
  std::vector<double> completeness;  // per threshold
  std::vector<double> fscore;        // per threshold, 2PR/(P+R) (0 if both 0)
  size_t num_result_samples = 0, num_truth_samples = 0;
};

// The scene's views as the metrics see them: per view, per point (absolute, mesh CRS), the
// unit direction from the point towards the view's sensor, or zero where the point falls
// outside the view's image (SceneViewDirections builds it from the scene's RPC images).
using ViewDirections = std::vector<std::vector<Eigen::Vector3f>>;
using ViewDirectionsFn = std::function<ViewDirections(const std::vector<Eigen::Vector3d>&)>;

// What the images can see, as photogrammetry needs it: a sample is seen by a view when it
// lies in the view's image, faces the sensor with the cosine of its normal and the
// direction at least kSeenMinCos (the engine's min_ray_cos default: grazing views
// ignored) and nothing of `mesh` lies between them; a height needs two views. A wall
// that one view or none sees is beyond any multi-view method.
inline constexpr int kSeenMinViews = 2;
inline constexpr double kSeenMinCos = 0.1;

// Per sample: 1 if at least min_views of the views see it on `mesh` (the sample's own
// surface; rays start 0.05 m off it along its normal).
std::vector<uint8_t> SeenByViews(const TriangleMesh& mesh, const SurfaceSamples& samples,
                                 const ViewDirections& directions, int min_views = kSeenMinViews,
                                 double min_cos = kSeenMinCos);

// Where the result's walls lie against the truth's: per truth facade sample, the signed
// distance along the sample's outward normal to the result surface (the nearer crossing of
// the line through the sample along its normal, within max_offset_m either way): positive
// where the result lies outside the true wall (a DSM's fattened walls, a wall not yet moved
// in), negative inside. Completeness says how many walls are near; this says which way the
// others are off. Quantiles over the samples with a crossing.
inline constexpr double kFacadeOffsetMaxM = 3.0;  // EvaluateMesh3d's search either way, m
inline constexpr double kFacadeOffsetFarM = 0.5;  // outside / inside beyond this, m

struct FacadeOffsets {
  double max_offset_m = 0;
  size_t num_samples = 0;  // facade samples of the truth
  size_t num_crossed = 0;  // of them, with the result within max_offset_m along the normal
  double p25_m = 0, median_m = 0, p75_m = 0;
  double outside_fraction = 0;  // of all num_samples: offset > kFacadeOffsetFarM
  double inside_fraction = 0;   // offset < -kFacadeOffsetFarM
};

FacadeOffsets MeasureFacadeOffsets(const TriangleMesh& result, const SurfaceSamples& samples,
                                   const std::vector<uint8_t>& is_facade, double max_offset_m);

struct Mesh3dMetrics {
  Mesh3dScores all;     // every sample
  Mesh3dScores facade;  // facade samples only (on either side; distances to the whole surface)
  // Samples with their own surface above them (UnderOverhang): arcades, the ground and
  // walls under balconies and eaves, what a 2.5D surface cannot hold. Completeness: of
  // the truth's such samples; accuracy: of the result's.
  Mesh3dScores under_overhang;
  // Facade samples at least two views see (SeenByViews, each surface's samples on itself):
  // the facades a multi-view method can reach. Empty (no samples) without views.
  Mesh3dScores seen_facade;
  FacadeOffsets facade_offset;  // the truth's facade samples, kFacadeOffsetMaxM
};

// Per sample of `mesh`: 1 if a vertical ray up from 0.1 m off the sample (along its
// normal, out of the surface) hits `mesh`, i.e. the mesh covers the sample from above.
std::vector<uint8_t> UnderOverhang(const TriangleMesh& mesh, const SurfaceSamples& samples);

// Both meshes in the same CRS (origins may differ). `views` (may be null): the scene's
// views, for seen_facade. Throws Error on invalid options.
Mesh3dMetrics EvaluateMesh3d(const TriangleMesh& result, const TriangleMesh& truth,
                             const Mesh3dOptions& options = {},
                             const ViewDirectionsFn* views = nullptr);

}  // namespace satmesh
