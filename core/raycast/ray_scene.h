#pragma once
// Embree 3 scene of one triangle mesh. Vertices can be updated in place and recommitted
// (no rebuild from scratch). Embree types stay inside the .cc.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "core/mesh/mesh.h"

namespace satmesh {

struct Ray {
  Eigen::Vector3f origin;
  Eigen::Vector3f direction;  // need not be unit; t is in units of |direction|
  float t_near = 0.f;
  float t_far = 1e30f;
};

struct RayHit {
  int face = -1;      // -1: miss
  float t = 0.f;      // ray parameter of the hit
  float u = 0.f, v = 0.f;  // barycentrics: hit = (1-u-v)*p0 + u*p1 + v*p2
  bool hit() const { return face >= 0; }
};

class RayScene {
 public:
  // Builds the BVH over mesh.vertices (tile-local floats; origin ignored).
  explicit RayScene(const TriangleMesh& mesh);
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  // Replaces vertex positions (same count, same faces) and refits the BVH.
  void UpdateVertices(const std::vector<Eigen::Vector3f>& vertices);

  // Closest hits for n rays (parallel over rays with OpenMP). Rays with non-finite
  // origin/direction are not traced (reported as misses), never passed to Embree.
  void Intersect(const Ray* rays, RayHit* hits, size_t n) const;
  RayHit Intersect(const Ray& ray) const;
  // The same for the rays of an image (row-major, width x height), traced in 4x4 blocks.
  void IntersectImage(const Ray* rays, int width, int height, RayHit* hits) const;
  // Any-hit occlusion test for n rays: occluded[i] = 1 if something lies in (t_near, t_far).
  void Occluded(const Ray* rays, unsigned char* occluded, size_t n) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace satmesh
