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
}

}  // namespace

void GradientAccumulator::Reset(size_t num_faces, size_t num_vertices) {
  faces_.assign(num_faces, FaceSlot());
  vertex_stamp_.assign(num_vertices, 0);
  seen_.assign(num_vertices, 0);
  direction_ = 0;
}

void GradientAccumulator::AddTo(const TriangleMesh& mesh,
                                const std::vector<Eigen::Vector3f>& face_normals,
                                std::vector<Eigen::Vector3d>* vertex_gradient,
                                std::vector<int>* seen) const {
  if (vertex_gradient) {
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      if (faces_[f].stamp == 0) continue;  // no pixel
      const Eigen::Vector3d normal = face_normals[f].cast<double>();
      const Eigen::Vector3i& face = mesh.faces[f];
      for (int k = 0; k < 3; ++k) (*vertex_gradient)[face[k]] += double(faces_[f].weights[k]) * normal;
    }
  }
  if (seen)
    for (size_t v = 0; v < seen_.size(); ++v) (*seen)[v] += seen_[v];
}

PairEnergy AccumulatePairGradient(const ViewLevel& view_i, const ViewLevel& view_j,
                                  const TriangleMesh& mesh,
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
  const RayHit* hits = view_i.hit_map.hits.data();
  for (size_t p = 0; p < warp.valid.size(); ++p) {
    if (!warp.valid[p]) continue;
    ++energy.num_valid_pixels;
    if (!accumulator) continue;
    // ∂b/∂V_k = db_dn · w_k · n^T (ray-triangle intersection moved by vertex k).
    const RayHit& hit = hits[p];
    accumulator->AddPixel(mesh.faces[hit.face], hit.face, hit.u, hit.v,
                          field.dM_db[p] * warp.db_dn[p]);
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
    return AccumulatePairGradient(view_i, view_j, mesh, face_normals, options, nullptr, workspace);
  GradientAccumulator accumulator;
  accumulator.Reset(mesh.faces.size(), mesh.vertices.size());
  const PairEnergy energy = AccumulatePairGradient(view_i, view_j, mesh, face_normals, options,
                                                   &accumulator, workspace);
  std::vector<int> seen(touched ? mesh.vertices.size() : 0, 0);
  accumulator.AddTo(mesh, face_normals, vertex_gradient, touched ? &seen : nullptr);
  if (touched)
    for (size_t v = 0; v < seen.size(); ++v)
      if (seen[v]) (*touched)[v] = 1;
  return energy;
}

}  // namespace satmesh
