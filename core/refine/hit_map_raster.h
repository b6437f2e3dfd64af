#pragma once
// Hit maps by z-buffer rasterization: the same answer as casting every pixel's ray
// (face, barycentrics, point, ray parameter of the first surface along the ray), found
// by projecting the mesh into the view through the RFM (the level's projection grid) and
// scanning each triangle's pixels. At the refinement's resolution a triangle covers ~2
// pixels, over which the RFM is affine, so the pixel-centre tests and the barycentrics
// are as exact as the projection grid (< 1e-3 px on real RPCs; the vertices' pixels are
// kept in float, < 2.5e-4 px more below 4096 px); the depth order is the distance along
// the view's mean ray (rays of one view are parallel to < 1e-3 rad over a tile). With
// AVX2, faces are set up 8 at a time and those with at most 2 x 2 pixel centres (nearly
// all) are tested without branches (docs/benchmarks-history.md, session 5).
#include <vector>

#include "core/mesh/mesh.h"
#include "core/refine/view_level.h"

namespace satmesh {

// A vertex projected into the view: GDAL pixel coordinates (NaN when it does not
// project), depth along the view's mean ray.
struct RasterVertex {
  float x, y, depth, unused;
};

// Scratch of the rasterizer (one per thread), reused across views and iterations.
struct RasterWorkspace {
  std::vector<RasterVertex> vertices;  // per mesh vertex
  std::vector<float> depth;            // z-buffer, per pixel
};

// Per face, what the hit-point pass reads, in one record: the pass visits pixels in
// image order, so it reads faces at random (one record instead of the face's vertex
// indices, three vertices and normal from four arrays).
struct FaceRecord {
  Eigen::Vector3f p0, e1, e2;  // hit point = p0 + u e1 + v e2
  Eigen::Vector3f normal;      // zero without face normals
};

// Scratch of RasterizeHitMaps and FollowHitMaps, reused across iterations.
struct HitMapScratch {
  std::vector<RasterWorkspace> threads;  // one per thread
  std::vector<FaceRecord> faces;         // per mesh face
};

// Fills view->hit_map (hits, surface) for the mesh's current vertices, like
// CastHitMap, and ray_cos too when face_normals is not null. Parallel over
// row bands with OpenMP.
void RasterizeHitMap(const TriangleMesh& mesh, ViewLevel* view, RasterWorkspace* workspace,
                     const std::vector<Eigen::Vector3f>* face_normals = nullptr);

// The hit maps of all views, one view per thread (a view alone does not keep two
// threads busy: every band must scan every face).
void RasterizeHitMaps(const TriangleMesh& mesh, std::vector<ViewLevel>* views,
                      HitMapScratch* scratch,
                      const std::vector<Eigen::Vector3f>* face_normals = nullptr);

// Between two rasterizations (or ray castings): each pixel keeps its face and barycentric
// coordinates (the gradient's weights), and its hit point moves along the pixel's ray onto
// the face's moved plane (the exact hit while the ray still crosses that face), with its ray
// parameter and ray cosine (when face_normals is not null; without them the point stays at
// its barycentrics). A vertex moves by at most max_step_gsd (0.5 level pixels) an
// iteration, typically a tenth of that, so a pixel's ray leaves its face only near the
// face's edges between rasterizations (RefineOptions::hit_maps_every). Moving the point
// with the face instead (at its barycentrics) put it off the ray by a share of the move
// each iteration: a plane under a 15-35 degree pair went 0.085 -> 0.23 m off between 15
// and 30 iterations (docs/benchmarks-history.md, session 33).
void FollowHitMaps(const TriangleMesh& mesh, std::vector<ViewLevel>* views,
                   HitMapScratch* scratch, const std::vector<Eigen::Vector3f>* face_normals);

// Per view: its hit map kept as it is, followed (FollowHitMaps) or rasterized anew
// (RasterizeHitMaps). A view kept keeps its faces: it can follow them later, however many
// iterations its hit map missed (RefineOptions::pairs_per_iteration).
enum class HitMapUpdate : uint8_t { kKeep, kFollow, kRasterize };
void UpdateHitMaps(const TriangleMesh& mesh, std::vector<ViewLevel>* views,
                   HitMapScratch* scratch, const std::vector<Eigen::Vector3f>* face_normals,
                   const std::vector<HitMapUpdate>& update);

}  // namespace satmesh
