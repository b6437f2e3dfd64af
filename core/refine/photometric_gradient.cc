#include "core/refine/photometric_gradient.h"

#include <algorithm>
#include <cmath>

#include "core/refine/warp.h"

namespace satmesh {
namespace {

void WarpIntoView(const ViewLevel& vi, const ViewLevel& vj,
                  const std::vector<Eigen::Vector3f>& face_normals,
                  const PhotometricOptions& options, PairWorkspace* ws) {
  const int w = vi.width(), h = vi.height();
  const size_t n = size_t(w) * h;
  ws->b.resize(n);  // meaningful only where valid
  ws->db_dn.resize(n);
  ws->valid.assign(n, 0);
  const bool have_cos = vi.hit_map.ray_cos.size() == n;
  const WarpContext context{&vi,
                            &vj,
                            &face_normals,
                            have_cos ? vi.hit_map.ray_cos.data() : nullptr,
                            float(options.visibility_tolerance_m * options.visibility_tolerance_m),
                            float(options.min_ray_cos),
                            ws->b.data(),
                            ws->db_dn.data(),
                            ws->valid.data()};
#pragma omp parallel for schedule(dynamic, 8)
  for (int row = 0; row < h; ++row) WarpRow(context, row, options.vectorized);
  // Moving shadows: the point's light differs under the two views' suns.
  const uint64_t marked = vi.hit_map.suns_marked;
  if (options.sunlit_only && vi.hit_map.sunlit.size() == n && vi.view < 64 && vj.view < 64 &&
      ((marked >> vi.view) & 1) && ((marked >> vj.view) & 1)) {
    const uint64_t* lit = vi.hit_map.sunlit.data();
    const int bi = vi.view, bj = vj.view;
    for (size_t p = 0; p < n; ++p)
      if (((lit[p] >> bi) ^ (lit[p] >> bj)) & 1) ws->valid[p] = 0;
  }
}

}  // namespace

void GradientAccumulator::Reset(const TriangleMesh& mesh, bool with_information) {
  mesh_ = &mesh;
  faces_.assign(mesh.faces.size(), FaceSlot());
  if (with_information) information_.assign(mesh.faces.size(), Eigen::Vector3f::Zero());
  else information_.clear();
  vertex_directions_.assign(mesh.vertices.size(), 0);
  seen_.assign(mesh.vertices.size(), 0);
  direction_ = -1;
  direction_bit_ = 0;
}

void GradientAccumulator::BeginDirection() {
  ++direction_;
  if (direction_ > 0 && direction_ % 32 == 0) CountDirections();
  direction_bit_ = 1u << (direction_ % 32);
}

void GradientAccumulator::CountDirections() {
  for (size_t f = 0; f < faces_.size(); ++f) {
    const uint32_t bits = faces_[f].directions;
    if (!bits) continue;
    faces_[f].directions = 0;
    for (int k = 0; k < 3; ++k) vertex_directions_[mesh_->faces[f][k]] |= bits;
  }
  for (size_t v = 0; v < seen_.size(); ++v) {
    seen_[v] += __builtin_popcount(vertex_directions_[v]);
    vertex_directions_[v] = 0;
  }
}

void GradientAccumulator::AddTo(const std::vector<Eigen::Vector3f>& face_normals,
                                std::vector<Eigen::Vector3d>* vertex_gradient,
                                std::vector<int>* seen, std::vector<double>* information) {
  if (!mesh_) return;
  if (information && !information_.empty()) {
    for (size_t f = 0; f < information_.size(); ++f) {
      const Eigen::Vector3i& face = mesh_->faces[f];
      for (int k = 0; k < 3; ++k) (*information)[face[k]] += double(information_[f][k]);
    }
  }
  if (vertex_gradient) {
    for (size_t f = 0; f < faces_.size(); ++f) {
      const Eigen::Vector3f& w = faces_[f].weights;
      if (w.x() == 0 && w.y() == 0 && w.z() == 0) continue;  // no pixel
      const Eigen::Vector3d normal = face_normals[f].cast<double>();
      const Eigen::Vector3i& face = mesh_->faces[f];
      for (int k = 0; k < 3; ++k) (*vertex_gradient)[face[k]] += double(w[k]) * normal;
    }
  }
  if (seen) {
    CountDirections();
    for (size_t v = 0; v < seen_.size(); ++v) (*seen)[v] += seen_[v];
  }
}

PairEnergy AccumulatePairGradient(const ViewLevel& view_i, const ViewLevel& view_j,
                                  const std::vector<Eigen::Vector3f>& face_normals,
                                  const PhotometricOptions& options,
                                  GradientAccumulator* accumulator, PairWorkspace* workspace) {
  PairWorkspace local;
  PairWorkspace& warp = workspace ? *workspace : local;
  WarpIntoView(view_i, view_j, face_normals, options, &warp);
  ComputeZnccFieldInto(view_i.image.pixels, warp.b, warp.valid, view_i.width(), view_i.height(),
                       options.zncc, &warp.field, &warp.zncc);
  const ZnccField& field = warp.field;
  PairEnergy energy;
  energy.sum_zncc = field.sum_zncc;
  energy.num_windows = field.num_windows;
  if (accumulator) accumulator->BeginDirection();
  const bool with_information = accumulator && accumulator->with_information();
  const RayHit* hits = view_i.hit_map.hits.data();
  const size_t n = warp.valid.size();
  constexpr size_t kAhead = 16;  // pixels: the face slots are random reads of a large array
  for (size_t p = 0; p < n; ++p) {
    if (accumulator && p + kAhead < n && warp.valid[p + kAhead])
      accumulator->Prefetch(hits[p + kAhead].face);
    if (!warp.valid[p]) continue;
    ++energy.num_valid_pixels;
    if (!accumulator) continue;
    // ∂b/∂V_k = db_dn · w_k · n^T (ray-triangle intersection moved by vertex k).
    const RayHit& hit = hits[p];
    accumulator->AddPixel(hit.face, hit.u, hit.v, field.dM_db[p] * warp.db_dn[p]);
    if (with_information) accumulator->AddInformation(hit.face, hit.u, hit.v, warp.db_dn[p]);
  }
  return energy;
}

PairEnergy AccumulatePhotometricGradient(const ViewLevel& view_i, const ViewLevel& view_j,
                                         const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3f>& face_normals,
                                         const PhotometricOptions& options,
                                         std::vector<Eigen::Vector3d>* vertex_gradient,
                                         std::vector<uint8_t>* touched,
                                         PairWorkspace* workspace) {
  if (!vertex_gradient && !touched)
    return AccumulatePairGradient(view_i, view_j, face_normals, options, nullptr, workspace);
  GradientAccumulator accumulator;
  accumulator.Reset(mesh);
  const PairEnergy energy = AccumulatePairGradient(view_i, view_j, face_normals, options,
                                                   &accumulator, workspace);
  std::vector<int> seen(touched ? mesh.vertices.size() : 0, 0);
  accumulator.AddTo(face_normals, vertex_gradient, touched ? &seen : nullptr);
  if (touched)
    for (size_t v = 0; v < seen.size(); ++v)
      if (seen[v]) (*touched)[v] = 1;
  return energy;
}

}  // namespace satmesh
