#include "core/raycast/ray_scene.h"

#include <embree3/rtcore.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/common/error.h"

namespace satmesh {
namespace {

constexpr int kPacket = 16;  // rays per rtcIntersect16/rtcOccluded16 call

void EmbreeErrorToSpdlog(void* /*user*/, RTCError code, const char* message) {
  spdlog::error("Embree error {}: {}", static_cast<int>(code), message ? message : "");
}

// One Embree device per process: creating a device starts Embree's thread pool and
// detects the ISA (costly), a device is thread-safe, and all scenes (one per tile or job)
// can share it. It holds no satmesh state, so sharing it is not a mutable global option.
RTCDevice SharedDevice() {
  struct Holder {
    RTCDevice device = nullptr;
    Holder() {
      device = rtcNewDevice(nullptr);
      if (device == nullptr) {
        ThrowError(ErrorCode::kInternal,
                   "Embree: rtcNewDevice failed (error " +
                       std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")");
      }
      rtcSetDeviceErrorFunction(device, EmbreeErrorToSpdlog, nullptr);
    }
    ~Holder() { rtcReleaseDevice(device); }  // scenes keep their own references
  };
  static Holder holder;  // thread-safe initialisation (C++11 magic statics)
  return holder.device;
}

bool IsFinite(const Eigen::Vector3f& v) { return v.allFinite(); }

// A ray Embree may see: finite origin and non-zero finite direction, no NaN range.
bool Traceable(const Ray& r) {
  return IsFinite(r.origin) && IsFinite(r.direction) && r.direction.squaredNorm() > 0.f &&
         !std::isnan(r.t_near) && !std::isnan(r.t_far) && std::isfinite(r.t_near) &&
         r.t_near <= r.t_far;
}

template <typename Packet>
void FillLane(Packet& p, int k, const Ray& r) {
  p.org_x[k] = r.origin.x();
  p.org_y[k] = r.origin.y();
  p.org_z[k] = r.origin.z();
  p.dir_x[k] = r.direction.x();
  p.dir_y[k] = r.direction.y();
  p.dir_z[k] = r.direction.z();
  p.tnear[k] = r.t_near;
  p.tfar[k] = r.t_far;
  p.time[k] = 0.f;
  p.mask[k] = 0xFFFFFFFFu;  // Debian's Embree is built with ray masks: 0 would miss all
  p.id[k] = 0;
  p.flags[k] = 0;
}

// Inactive lanes still get finite, harmless values (Embree never reads NaN from us).
const Ray kDummyRay{Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitZ(), 0.f, 0.f};

void CheckVertices(const std::vector<Eigen::Vector3f>& vertices) {
  for (size_t i = 0; i < vertices.size(); ++i) {
    SATMESH_CHECK(IsFinite(vertices[i]), ErrorCode::kInvalidInput,
                  "RayScene: vertex " + std::to_string(i) + " is not finite");
  }
}

}  // namespace

struct RayScene::Impl {
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;  // null for a mesh without faces (everything misses)
  float* vertex_buffer = nullptr;  // owned by Embree (padded for 16-byte loads)
  size_t num_vertices = 0;
};

RayScene::RayScene(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  CheckVertices(mesh.vertices);
  const long long nv = static_cast<long long>(mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3i& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      SATMESH_CHECK(t[k] >= 0 && t[k] < nv, ErrorCode::kInvalidInput,
                    "RayScene: face " + std::to_string(f) + " has vertex index " +
                        std::to_string(t[k]) + " out of range [0, " + std::to_string(nv) +
                        ")");
    }
  }
  RTCDevice device = SharedDevice();
  impl_->num_vertices = mesh.vertices.size();
  impl_->scene = rtcNewScene(device);
  // DYNAMIC: two-level BVH so the refit-quality geometry is refitted, not rebuilt.
  // ROBUST: watertight hits on shared edges/vertices (vertical rays through DSM vertices).
  rtcSetSceneFlags(impl_->scene, RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(impl_->scene, RTC_BUILD_QUALITY_MEDIUM);
  if (!mesh.faces.empty()) {
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_REFIT);
    impl_->vertex_buffer = static_cast<float*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
        mesh.vertices.size()));
    auto* index = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
        mesh.faces.size()));
    SATMESH_CHECK(impl_->vertex_buffer && index, ErrorCode::kInternal,
                  "RayScene: Embree could not allocate buffers");
    for (size_t i = 0; i < mesh.vertices.size(); ++i) {
      std::memcpy(impl_->vertex_buffer + 3 * i, mesh.vertices[i].data(), 3 * sizeof(float));
    }
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      for (int k = 0; k < 3; ++k) index[3 * f + k] = static_cast<unsigned>(mesh.faces[f][k]);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometry(impl_->scene, g);
    impl_->geometry = g;
  }
  rtcCommitScene(impl_->scene);
}

RayScene::~RayScene() {
  if (impl_->geometry) rtcReleaseGeometry(impl_->geometry);
  if (impl_->scene) rtcReleaseScene(impl_->scene);
}

void RayScene::UpdateVertices(const std::vector<Eigen::Vector3f>& vertices) {
  SATMESH_CHECK(vertices.size() == impl_->num_vertices, ErrorCode::kInvalidArgument,
                "RayScene::UpdateVertices: got " + std::to_string(vertices.size()) +
                    " vertices, the scene has " + std::to_string(impl_->num_vertices));
  CheckVertices(vertices);
  if (!impl_->geometry) return;
  for (size_t i = 0; i < vertices.size(); ++i) {
    std::memcpy(impl_->vertex_buffer + 3 * i, vertices[i].data(), 3 * sizeof(float));
  }
  rtcUpdateGeometryBuffer(impl_->geometry, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(impl_->geometry);
  rtcCommitScene(impl_->scene);  // refits (REFIT build quality), no rebuild
}

namespace {

// Closest hits of packets of 16 rays; ray_index(packet, lane) gives the ray of a lane
// (or a value >= n for an empty lane). Parallel over packets.
template <typename RayIndex>
void IntersectPackets(RTCScene scene, const Ray* rays, RayHit* hits, size_t n,
                      long long num_packets, RayIndex ray_index) {
#pragma omp parallel for schedule(dynamic, 64)
  for (long long b = 0; b < num_packets; ++b) {
    alignas(64) int valid[kPacket];
    size_t index[kPacket];
    RTCRayHit16 rh;
    bool any = false;
    for (int k = 0; k < kPacket; ++k) {
      index[k] = ray_index(b, k);
      const bool ok = index[k] < n && Traceable(rays[index[k]]);
      valid[k] = ok ? -1 : 0;
      any |= ok;
      FillLane(rh.ray, k, ok ? rays[index[k]] : kDummyRay);
      rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    if (any) {
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
      rtcIntersect16(valid, scene, &context, &rh);
    }
    for (int k = 0; k < kPacket; ++k) {
      if (index[k] >= n) continue;
      RayHit& h = hits[index[k]];
      h = RayHit{};
      if (valid[k] && rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {
        h.face = static_cast<int>(rh.hit.primID[k]);
        h.t = rh.ray.tfar[k];
        h.u = rh.hit.u[k];
        h.v = rh.hit.v[k];
      }
    }
  }
}

}  // namespace

void RayScene::Intersect(const Ray* rays, RayHit* hits, size_t n) const {
  const long long packets = static_cast<long long>((n + kPacket - 1) / kPacket);
  IntersectPackets(impl_->scene, rays, hits, n, packets, [](long long b, int k) {
    return static_cast<size_t>(b) * kPacket + k;
  });
}

void RayScene::IntersectImage(const Ray* rays, int width, int height, RayHit* hits) const {
  // 4x4 pixel blocks: neighbouring rays traverse the same BVH nodes.
  const int blocks_x = (width + 3) / 4, blocks_y = (height + 3) / 4;
  const size_t n = size_t(width) * height;
  IntersectPackets(impl_->scene, rays, hits, n, static_cast<long long>(blocks_x) * blocks_y,
                   [&](long long b, int k) {
                     const int col = int(b % blocks_x) * 4 + (k & 3);
                     const int row = int(b / blocks_x) * 4 + (k >> 2);
                     return (col < width && row < height) ? size_t(row) * width + col : n;
                   });
}

RayHit RayScene::Intersect(const Ray& ray) const {
  RayHit hit;
  Intersect(&ray, &hit, 1);
  return hit;
}

void RayScene::Occluded(const Ray* rays, unsigned char* occluded, size_t n) const {
  const long long blocks = static_cast<long long>((n + kPacket - 1) / kPacket);
  RTCScene scene = impl_->scene;
#pragma omp parallel for schedule(dynamic, 64)
  for (long long b = 0; b < blocks; ++b) {
    alignas(64) int valid[kPacket];
    RTCRay16 r;
    const size_t first = static_cast<size_t>(b) * kPacket;
    bool any = false;
    for (int k = 0; k < kPacket; ++k) {
      const size_t i = first + k;
      const bool ok = i < n && Traceable(rays[i]);
      valid[k] = ok ? -1 : 0;
      any |= ok;
      FillLane(r, k, ok ? rays[i] : kDummyRay);
    }
    if (any) {
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      rtcOccluded16(valid, scene, &context, &r);
    }
    // Embree sets tfar = -inf for occluded rays.
    for (int k = 0; k < kPacket && first + k < n; ++k) {
      occluded[first + k] =
          (valid[k] && r.tfar[k] == -std::numeric_limits<float>::infinity()) ? 1 : 0;
    }
  }
}

}  // namespace satmesh
