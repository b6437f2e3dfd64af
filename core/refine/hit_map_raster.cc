#include "core/refine/hit_map_raster.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/refine/lattice_avx2.h"
#include "core/refine/warp.h"

namespace satmesh {
namespace {

// Edge function e(p) = A x + B y + C of the directed edge s -> t: twice the signed area
// of (s, t, p). The coefficients come from the lower vertex index first, so the two
// triangles of an edge evaluate the same numbers (with opposite signs): a pixel centre
// on the edge is inside one of them or both, never neither.
struct Edge {
  double A, B, C;
  double operator()(double x, double y) const { return A * x + B * y + C; }
};
inline Edge MakeEdge(const Eigen::Vector2d* pixels, int s, int t) {
  const bool swap = s > t;
  const Eigen::Vector2d& a = pixels[swap ? t : s];
  const Eigen::Vector2d& b = pixels[swap ? s : t];
  const double A = a.y() - b.y(), B = b.x() - a.x();
  const double C = -(A * a.x() + B * a.y());
  return swap ? Edge{-A, -B, -C} : Edge{A, B, C};
}

// floor and ceil of finite values in int range, without libm calls (no SSE4.1 in the
// portable build).
inline int FloorInt(double a) { const int i = int(a); return i - (a < i); }
inline int CeilInt(double a) { const int i = int(a); return i + (a > i); }

// The view's mean ray direction (unit), from the central pixel's ray.
Eigen::Vector3f MeanRayDirection(const ViewLevel& view) {
  const size_t centre = size_t(view.height() / 2) * view.width() + view.width() / 2;
  return view.ray_directions[centre].normalized();
}

// Rasterizes every face into rows [row_begin, row_end): face id, barycentrics and depth
// of the nearest face per pixel centre.
void RasterizeBand(const TriangleMesh& mesh, const RasterWorkspace& ws, int width, int row_begin,
                   int row_end, std::vector<RayHit>* hits, float* depth) {
  const Eigen::Vector2d* px = ws.pixels.data();
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& face = mesh.faces[f];
    const Eigen::Vector2d &a = px[face[0]], &b = px[face[1]], &c = px[face[2]];
    const double min_y = std::min({a.y(), b.y(), c.y()}), max_y = std::max({a.y(), b.y(), c.y()});
    // Rows whose centre (row + 0.5) lies in [min_y, max_y]; NaN fails both tests.
    if (!(max_y >= row_begin + 0.5 && min_y <= row_end - 0.5)) continue;
    const double min_x = std::min({a.x(), b.x(), c.x()}), max_x = std::max({a.x(), b.x(), c.x()});
    if (!(max_x >= 0.5 && min_x <= width - 0.5)) continue;
    const int r0 = std::max(row_begin, CeilInt(std::max(min_y, -1.0) - 0.5));
    const int r1 = std::min(row_end - 1, FloorInt(std::min(max_y, double(row_end)) - 0.5));
    const int c0 = std::max(0, CeilInt(std::max(min_x, -1.0) - 0.5));
    const int c1 = std::min(width - 1, FloorInt(std::min(max_x, double(width)) - 0.5));
    if (r0 > r1 || c0 > c1) continue;  // no pixel centre in the box (small faces)
    const float d0 = ws.vertex_depth[face[0]], d1 = ws.vertex_depth[face[1]],
                d2 = ws.vertex_depth[face[2]];
    const Edge e0 = MakeEdge(px, face[1], face[2]);  // weight of vertex 0
    const Edge e1 = MakeEdge(px, face[2], face[0]);  // of vertex 1
    const Edge e2 = MakeEdge(px, face[0], face[1]);  // of vertex 2
    // Twice the signed area; the weights w_k share its sign inside the triangle.
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (area == 0) continue;  // edge-on
    const double sign = area > 0 ? 1.0 : -1.0, inv_area = 1.0 / area;
    // The pixel centre (row, col), known to be inside: depth test and write.
    auto draw = [&](int row, int col, double w1, double w2) {
      const float u = float(w1 * inv_area), v = float(w2 * inv_area);
      const float z = d0 + u * (d1 - d0) + v * (d2 - d0);
      const size_t p = size_t(row) * width + col;
      if (!(z < depth[p])) return;
      depth[p] = z;
      (*hits)[p] = RayHit{int(f), 0.f, u, v};
    };
    if (r1 - r0 <= 1 && c1 - c0 <= 1) {
      // At most 2 x 2 pixel centres (nearly every face at the refinement's resolution):
      // the four are tested without branches, then only the inside ones are drawn.
      unsigned inside = 0;
      for (int k = 0; k < 4; ++k) {
        const int row = r0 + (k >> 1), col = c0 + (k & 1);
        const double x = col + 0.5, y = row + 0.5;
        inside |= unsigned((row <= r1) & (col <= c1) & (sign * e0(x, y) >= 0) &
                           (sign * e1(x, y) >= 0) & (sign * e2(x, y) >= 0))
                  << k;
      }
      for (; inside; inside &= inside - 1) {
        const int k = __builtin_ctz(inside);
        const int row = r0 + (k >> 1), col = c0 + (k & 1);
        draw(row, col, e1(col + 0.5, row + 0.5), e2(col + 0.5, row + 0.5));
      }
      continue;
    }
    for (int row = r0; row <= r1; ++row) {
      const double y = row + 0.5;
      for (int col = c0; col <= c1; ++col) {
        const double x = col + 0.5;
        const double w0 = e0(x, y), w1 = e1(x, y), w2 = e2(x, y);
        if ((sign * w0 >= 0) & (sign * w1 >= 0) & (sign * w2 >= 0)) draw(row, col, w1, w2);
      }
    }
  }
}

// The vertex's pixel through the double lattice (exact RPC outside it) and its depth.
inline void ProjectVertex(const ViewLevel& view, const Eigen::Vector3f& along,
                          const Eigen::Vector3f& p, Eigen::Vector2d* pixel, float* depth) {
  Eigen::Matrix<double, 2, 3> unused;
  *pixel = p.allFinite() ? view.projection.PixelFromLocal(p.cast<double>(), &unused)
                         : Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  *depth = along.dot(p);
}

#ifdef SATMESH_HAVE_AVX2_LATTICE
// Vertices [0, n - n % 8) 8 at a time through the float lattice; the lanes outside it
// (and non-finite vertices) take ProjectVertex.
SATMESH_AVX2 void ProjectVerticesAvx2(const std::vector<Eigen::Vector3f>& vertices,
                                      const ViewLevel& view, const Eigen::Vector3f& along,
                                      long begin, long end, Eigen::Vector2d* pixels, float* depth) {
  const LatticeAvx2 lattice(view.projection);
  const __m256 all = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
  for (long v = begin; v < end; v += 8) {
    __m256 X[3], x, y, J[6];
    LoadPoints3(vertices[v].data(), &X[0], &X[1], &X[2]);
    const __m256 inside = lattice.Project(X, all, &x, &y, J);
    const __m256 d = _mm256_fmadd_ps(X[2], _mm256_set1_ps(along.z()),
                                     _mm256_fmadd_ps(X[1], _mm256_set1_ps(along.y()),
                                                     _mm256_mul_ps(X[0], _mm256_set1_ps(along.x()))));
    _mm256_storeu_ps(depth + v, d);
    alignas(32) float xs[8], ys[8];
    _mm256_store_ps(xs, x);
    _mm256_store_ps(ys, y);
    const int in = _mm256_movemask_ps(inside);
    for (int k = 0; k < 8; ++k) {
      if (in >> k & 1)
        pixels[v + k] = Eigen::Vector2d(xs[k], ys[k]);
      else
        ProjectVertex(view, along, vertices[v + k], &pixels[v + k], &depth[v + k]);
    }
  }
}
#endif

// Every vertex's pixel and depth, in parallel.
void ProjectVertices(const TriangleMesh& mesh, const ViewLevel& view, const Eigen::Vector3f& along,
                     RasterWorkspace* ws) {
  const long nv = long(mesh.vertices.size());
  ws->pixels.resize(nv);
  ws->vertex_depth.resize(nv);
  constexpr long kChunk = 4096;  // a multiple of 8
#pragma omp parallel for schedule(static)
  for (long begin = 0; begin < nv; begin += kChunk) {
    const long end = std::min(nv, begin + kChunk);
    long v = begin;
#ifdef SATMESH_HAVE_AVX2_LATTICE
    if (WarpHasAvx2()) {
      v = begin + (end - begin) / 8 * 8;
      ProjectVerticesAvx2(mesh.vertices, view, along, begin, v, ws->pixels.data(),
                          ws->vertex_depth.data());
    }
#endif
    for (; v < end; ++v)
      ProjectVertex(view, along, mesh.vertices[v], &ws->pixels[v], &ws->vertex_depth[v]);
  }
}

}  // namespace

void RasterizeHitMap(const TriangleMesh& mesh, ViewLevel* view, RasterWorkspace* workspace,
                     const std::vector<Eigen::Vector3f>* face_normals) {
  RasterWorkspace& ws = *workspace;
  HitMap& map = view->hit_map;
  const int w = view->width(), h = view->height();
  const size_t n = size_t(w) * h;
  map.hits.assign(n, RayHit{});
  map.points.resize(n);
  map.faces.resize(n);
  if (face_normals) map.ray_cos.resize(n);
  ws.depth.assign(n, std::numeric_limits<float>::infinity());
  ProjectVertices(mesh, *view, MeanRayDirection(*view), &ws);
#pragma omp parallel
  {
    // One band of rows per thread; every thread scans all faces (a cheap bounds test).
    const int threads = omp_get_num_threads(), t = omp_get_thread_num();
    const int row_begin = int(long(h) * t / threads), row_end = int(long(h) * (t + 1) / threads);
    RasterizeBand(mesh, ws, w, row_begin, row_end, &map.hits, ws.depth.data());
  }
  // The hit point on the face, its parameter along the pixel's ray (unit direction from
  // the plane z = z_high), and the ray cosine.
  const float z_high = float(view->camera.z_high());
#pragma omp parallel for schedule(static)
  for (long p = 0; p < long(n); ++p) {
    RayHit& hit = map.hits[p];
    map.faces[p] = hit.face;
    if (face_normals) map.ray_cos[p] = RayCosine(view->ray_directions[p], hit.face, *face_normals);
    if (!hit.hit()) continue;
    const Eigen::Vector3i& f = mesh.faces[hit.face];
    const Eigen::Vector3f& p0 = mesh.vertices[f[0]];
    const Eigen::Vector3f X =
        p0 + hit.u * (mesh.vertices[f[1]] - p0) + hit.v * (mesh.vertices[f[2]] - p0);
    const Eigen::Vector3f& direction = view->ray_directions[p];
    hit.t = (X.z() - z_high) / direction.z();
    map.points[p] = X;
  }
}

void RasterizeHitMaps(const TriangleMesh& mesh, std::vector<ViewLevel>* views,
                      std::vector<RasterWorkspace>* workspaces,
                      const std::vector<Eigen::Vector3f>* face_normals) {
  workspaces->resize(omp_get_max_threads());
  // Inside, RasterizeHitMap's own parallel regions run on the calling thread alone.
#pragma omp parallel for schedule(dynamic, 1)
  for (size_t v = 0; v < views->size(); ++v)
    RasterizeHitMap(mesh, &(*views)[v], &(*workspaces)[omp_get_thread_num()], face_normals);
}

}  // namespace satmesh
