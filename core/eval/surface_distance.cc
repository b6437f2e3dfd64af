#include "core/eval/surface_distance.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <embree3/rtcore.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <string>

#include "core/common/error.h"

namespace satmesh {
namespace {

using K = CGAL::Simple_cartesian<double>;
using TriIt = std::vector<K::Triangle_3>::const_iterator;
using AabbTree = CGAL::AABB_tree<CGAL::AABB_traits<K, CGAL::AABB_triangle_primitive<K, TriIt>>>;

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3f ClosestPointOnTriangle(const Eigen::Vector3f& p, const Eigen::Vector3f& a,
                                       const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f ab = b - a, ac = c - a, ap = p - a;
  const float d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3f bp = p - b;
  const float d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3f cp = p - c;
  const float d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = 1.f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct QueryState {
  const std::vector<Eigen::Vector3f>* vertices;
  const std::vector<Eigen::Vector3i>* faces;
  float best;
};

bool PointQueryCallback(RTCPointQueryFunctionArguments* args) {
  auto* s = static_cast<QueryState*>(args->userPtr);
  const Eigen::Vector3i& f = (*s->faces)[args->primID];
  const Eigen::Vector3f q(args->query->x, args->query->y, args->query->z);
  const auto& v = *s->vertices;
  const float d = (q - ClosestPointOnTriangle(q, v[f[0]], v[f[1]], v[f[2]])).norm();
  if (d >= args->query->radius) return false;
  args->query->radius = d;
  s->best = d;
  return true;
}

}  // namespace

struct SurfaceDistance::Impl {
  DistanceBackend backend;
  Eigen::Vector3d origin;
  std::vector<Eigen::Vector3f> vertices;  // relative to origin
  std::vector<Eigen::Vector3i> faces;     // non-degenerate only
  // CGAL
  std::vector<K::Triangle_3> triangles;
  std::unique_ptr<AabbTree> tree;
  // Embree
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  void BuildCgal() {
    triangles.reserve(faces.size());
    for (const auto& f : faces) {
      auto p = [&](int k) {
        const Eigen::Vector3f& v = vertices[f[k]];
        return K::Point_3(v.x(), v.y(), v.z());
      };
      triangles.emplace_back(p(0), p(1), p(2));
    }
    tree = std::make_unique<AabbTree>(triangles.begin(), triangles.end());
    tree->build();
    tree->accelerate_distance_queries();
  }

  void BuildEmbree() {
    device = rtcNewDevice(nullptr);
    SATMESH_CHECK(device, ErrorCode::kInternal, "rtcNewDevice failed");
    scene = rtcNewScene(device);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
        vertices.size() + 1));  // +1: Embree may read 16 bytes of the last vertex
    for (size_t k = 0; k < vertices.size(); ++k)
      for (int c = 0; c < 3; ++c) vb[3 * k + c] = vertices[k][c];
    auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), faces.size()));
    for (size_t k = 0; k < faces.size(); ++k)
      for (int c = 0; c < 3; ++c) ib[3 * k + c] = unsigned(faces[k][c]);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene);
  }

  float DistanceCgal(const Eigen::Vector3f& q) const {
    return float(std::sqrt(tree->squared_distance(K::Point_3(q.x(), q.y(), q.z()))));
  }

  float DistanceEmbree(const Eigen::Vector3f& q, float max_d) const {
    RTCPointQuery query;
    query.x = q.x();
    query.y = q.y();
    query.z = q.z();
    query.time = 0.f;
    query.radius = max_d;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    QueryState state{&vertices, &faces, std::numeric_limits<float>::infinity()};
    rtcPointQuery(scene, &query, &context, PointQueryCallback, &state);
    return state.best;
  }
};

SurfaceDistance::SurfaceDistance(const TriangleMesh& mesh, DistanceBackend backend)
    : impl_(std::make_unique<Impl>()) {
  ValidateMesh(mesh, "SurfaceDistance mesh");
  impl_->backend = backend;
  impl_->origin = mesh.origin;
  impl_->vertices = mesh.vertices;
  for (const auto& f : mesh.faces) {
    const auto& v = mesh.vertices;
    if ((v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]).squaredNorm() > 0) impl_->faces.push_back(f);
  }
  if (impl_->faces.empty()) return;
  if (backend == DistanceBackend::kCgalAabb) impl_->BuildCgal();
  else impl_->BuildEmbree();
}

SurfaceDistance::~SurfaceDistance() = default;

std::vector<float> SurfaceDistance::Distances(const std::vector<Eigen::Vector3d>& points,
                                              double max_distance_m) const {
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> d(points.size(), inf);
  if (impl_->faces.empty()) return d;
  const float max_d = std::isfinite(max_distance_m) ? float(max_distance_m) : inf;
  const Impl& im = *impl_;
#pragma omp parallel for schedule(dynamic, 256)
  for (long long k = 0; k < (long long)points.size(); ++k) {
    const Eigen::Vector3f q = (points[k] - im.origin).cast<float>();
    if (!q.allFinite()) continue;
    d[k] = im.backend == DistanceBackend::kCgalAabb ? im.DistanceCgal(q)
                                                    : im.DistanceEmbree(q, max_d);
  }
  return d;
}

}  // namespace satmesh
