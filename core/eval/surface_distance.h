#pragma once
// Unsigned point-to-surface distance to a triangle mesh (closest point on any face).
// Backends: CGAL's AABB tree or Embree's rtcPointQuery; third-party types stay in the .cc.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/mesh/mesh.h"

namespace satmesh {

enum class DistanceBackend {
  kCgalAabb,  // CGAL::AABB_tree closest point (exact, double)
  kEmbree,    // Embree rtcPointQuery with a closest-point-on-triangle callback (float)
};

class SurfaceDistance {
 public:
  // Builds the search structure over the mesh's faces (degenerate faces are skipped).
  SurfaceDistance(const TriangleMesh& mesh, DistanceBackend backend = DistanceBackend::kEmbree);
  ~SurfaceDistance();
  SurfaceDistance(const SurfaceDistance&) = delete;
  SurfaceDistance& operator=(const SurfaceDistance&) = delete;

  // Distance in metres from each point (absolute, in the mesh's CRS) to the surface,
  // parallel over points. Distances above max_distance_m may be reported as any value
  // >= max_distance_m (the search stops there); +inf for an empty mesh.
  std::vector<float> Distances(const std::vector<Eigen::Vector3d>& points,
                               double max_distance_m) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace satmesh
