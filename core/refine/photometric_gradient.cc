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

void GradientAccumulator::Reset(const TriangleMesh& mesh, const VertexAdjacency& adjacency,
                                bool with_information) {
  mesh_ = &mesh;
  adjacency_ = &adjacency;
  faces_.assign(mesh.faces.size(), FaceSlot());
  if (with_information) information_.assign(mesh.faces.size(), Eigen::Vector3f::Zero());
  else information_.clear();
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
  const VertexAdjacency& adjacency = *adjacency_;
#pragma omp parallel for schedule(static)
  for (long v = 0; v < long(seen_.size()); ++v) {
    uint32_t directions = 0;
    for (int k = adjacency.face_offsets[v]; k < adjacency.face_offsets[v + 1]; ++k)
      directions |= faces_[adjacency.faces[k]].directions;
    seen_[v] += __builtin_popcount(directions);
  }
#pragma omp parallel for schedule(static)
  for (long f = 0; f < long(faces_.size()); ++f) faces_[f].directions = 0;
}

void GradientAccumulator::AddTo(const std::vector<Eigen::Vector3f>& face_normals,
                                std::vector<Eigen::Vector3d>* vertex_gradient,
                                std::vector<int>* seen, std::vector<double>* information) {
  if (!mesh_) return;
  const VertexAdjacency& adjacency = *adjacency_;
  const bool with_information = information && !information_.empty();
  // Each vertex gathers from its faces (ascending, as a scatter over the faces would add
  // them: the same sums to the bit), so that the vertices run in parallel.
#pragma omp parallel for schedule(static)
  for (long v = 0; v < long(mesh_->vertices.size()); ++v) {
    uint32_t directions = 0;  // since the last CountDirections
    Eigen::Vector3d g = vertex_gradient ? (*vertex_gradient)[v] : Eigen::Vector3d::Zero();
    double info = with_information ? (*information)[v] : 0.0;
    const int begin = adjacency.face_offsets[v], end = adjacency.face_offsets[v + 1];
    for (int k = begin; k < end; ++k) {
      const int f = adjacency.faces[k];
      if (k > begin && adjacency.faces[k - 1] == f) continue;  // a degenerate face, done
      const FaceSlot& slot = faces_[f];
      directions |= slot.directions;
      const Eigen::Vector3i& face = mesh_->faces[f];
      const Eigen::Vector3f& w = slot.weights;
      const bool weighted = !(w.x() == 0 && w.y() == 0 && w.z() == 0);  // else no pixel
      const auto add = [&](int c) {  // corner c is v
        if (with_information) info += double(information_[f][c]);
        if (weighted) g += double(w[c]) * face_normals[f].cast<double>();
      };
      const int at1 = face[1] == v, at2 = face[2] == v;
      if (int(face[0] == v) + at1 + at2 == 1) {
        add(at1 + 2 * at2);  // the corner without a branch to mispredict
      } else {
        for (int c = 0; c < 3; ++c)  // v at two corners of a degenerate face
          if (face[c] == v) add(c);
      }
    }
    if (vertex_gradient) (*vertex_gradient)[v] = g;
    if (with_information) (*information)[v] = info;
    if (seen) (*seen)[v] += seen_[v] + __builtin_popcount(directions);
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
  const VertexAdjacency adjacency = BuildVertexAdjacency(mesh);
  GradientAccumulator accumulator;
  accumulator.Reset(mesh, adjacency);
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
