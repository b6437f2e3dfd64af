#pragma once
// One view at one pyramid level: normalised image, level RPC, virtual camera, the ray
// directions of all its pixels (fixed for the level), and the hit map of the current mesh.
#include <cstdint>
#include <vector>

#include "core/image/image.h"
#include "core/mesh/mesh.h"
#include "core/raycast/ray_scene.h"
#include "core/refine/projection_grid.h"
#include "core/refine/virtual_camera.h"
#include "core/rpc/rpc_model.h"

namespace satmesh {

// A pixel's hit point and face in one 16-byte record: other views' visibility lookups
// land at random pixels and read both, from one cache line.
struct SurfacePoint {
  Eigen::Vector3f point;  // frame coordinates, valid where face >= 0
  int face = -1;          // hits[i].face again
};

struct HitMap {
  std::vector<RayHit> hits;             // one per pixel, row-major
  std::vector<SurfacePoint> surface;    // per pixel
  std::vector<float> ray_cos;           // ray · face normal per hit pixel (RayCosine; filled
                                        // by CastHitMap / RasterizeHitMap given the normals);
                                        // shared by all pair-directions from this view
  std::vector<uint64_t> sunlit;         // per pixel, when marked (sunlight.h, MarkSunlight):
                                        // bit s set where sun s lights the hit point
  uint64_t suns_marked = 0;             // the suns s that sunlit says something about
};

struct ViewLevel {
  int view = 0;
  int level = 0;
  ImageF image;        // normalised radiometry, pyramid level
  RpcModel rpc;        // pixel coordinates of this level
  VirtualCamera camera;
  ProjectionGrid projection;  // fast pixel_from_local of this level
  std::vector<Eigen::Vector3f> ray_directions;  // unit, per pixel (the virtual camera's);
                                                // rays start on the plane camera.z_high()
  HitMap hit_map;

  int width() const { return image.width; }
  int height() const { return image.height; }
};

// The box the surface lives in for a level's rays and projection lattice: the mesh's
// extent +-10 m horizontally, the height range [min_z, max_z] (widened to the mesh) with
// a margin of 2 m + 10% of the range.
void SurfaceBox(const TriangleMesh& mesh, double min_z, double max_z, Eigen::Vector3d* box_min,
                Eigen::Vector3d* box_max);

// Builds the level data (rays from the virtual camera, projection lattice over the box
// [box_min, box_max] of the frame) of one view. The box's z range bounds the rays.
ViewLevel MakeViewLevel(int view, int level, ImageF image_level, const RpcModel& rpc_window,
                        const LocalFrame& frame, const Eigen::Vector3d& box_min,
                        const Eigen::Vector3d& box_max, int grid_px);

// The full rays of every pixel (origin on the upper plane), for Embree.
std::vector<Ray> PixelRays(const ViewLevel& view);

// Casts all rays of the view against the scene (the paper's dominant cost: once per view
// per iteration, shared by all pairs), and fills ray_cos when face_normals is not null
// (one random normal read per pixel per iteration instead of one per pair-direction).
// Returns the seconds spent in Embree's Intersect.
double CastHitMap(const RayScene& scene, ViewLevel* view,
                  const std::vector<Eigen::Vector3f>* face_normals = nullptr);

// hit_map.ray_cos of a pixel: ray · face normal where it hits, 0 where it misses.
inline float RayCosine(const Eigen::Vector3f& ray_direction, int face,
                       const std::vector<Eigen::Vector3f>& face_normals) {
  return face >= 0 ? ray_direction.dot(face_normals[face]) : 0.f;
}

}  // namespace satmesh
