#include "core/refine/photometric_gradient.h"

#include <algorithm>
#include <cmath>

#include "core/common/simd.h"

namespace satmesh {
namespace {

// What one pair-direction's warp reads and writes, as plain pointers.
struct WarpContext {
  const ViewLevel* vi;
  const ViewLevel* vj;
  const RayHit* hits_i;
  const float* cos_i;  // null: computed from the face normals
  const std::vector<Eigen::Vector3f>* face_normals;
  const int* faces_j;
  const Eigen::Vector3f* points_j;
  float tol2, min_cos;
  PairWorkspace* out;
};

// Projects one row of view i's hit points into j, tests visibility, samples j. Per
// pixel: b, valid, and db_dn = ∂b per unit move of the face along its normal. The AVX2
// copy also gets VEX scalar code and roundsd for the projection's floors.
SATMESH_AVX2_CLONE
void WarpRow(const WarpContext& c, int row) {
  const ViewLevel& vi = *c.vi;
  const ViewLevel& vj = *c.vj;
  const int w = vi.width(), wj = vj.width();
  const double max_x = vj.width() - 1.0, max_y = vj.height() - 1.0;
  const float* image_j = vj.image.pixels.data();
  PairWorkspace& out = *c.out;
  for (int col = 0; col < w; ++col) {
    const size_t p = size_t(row) * w + col;
    const int face = c.hits_i[p].face;
    if (face < 0) continue;
    const Eigen::Vector3f& ray_dir = vi.rays[p].direction;
    const float cos_ray = c.cos_i ? c.cos_i[p] : ray_dir.dot((*c.face_normals)[face]);
    if (cos_ray > -c.min_cos) continue;  // grazing or back-facing
    const Eigen::Vector3f& X = vi.hit_map.points[p];
    Eigen::Matrix<double, 2, 3> pixel_from_local;
    const Eigen::Vector2d xj = vj.projection.PixelFromLocal(X.cast<double>(), &pixel_from_local);
    if (!(xj.x() >= 1.0 && xj.y() >= 1.0 && xj.x() < max_x && xj.y() < max_y)) continue;
    // Visibility in j: j's own ray through that pixel must hit the same surface point
    // (the same face needs no point read).
    const size_t q = size_t(int(xj.y())) * wj + int(xj.x());
    const int face_j = c.faces_j[q];
    if (face_j != face && (face_j < 0 || (c.points_j[q] - X).squaredNorm() > c.tol2)) continue;
    // Bilinear sample of j (centre-origin coordinates, at least half a pixel inside)
    // with the exact derivatives of the interpolant.
    const double u = xj.x() - 0.5, v = xj.y() - 0.5;
    const int iu = int(u), iv = int(v);
    const float fx = float(u - iu), fy = float(v - iv);
    const float* s = image_j + size_t(iv) * wj + iu;
    const float p00 = s[0], p10 = s[1], p01 = s[wj], p11 = s[wj + 1];
    const float top = p00 + fx * (p10 - p00), bottom = p01 + fx * (p11 - p01);
    const float db_dx = (p10 - p00) + fy * ((p11 - p01) - (p10 - p00)), db_dy = bottom - top;
    // DΠ_j in the local frame (the projection holds the chain rule through the frame),
    // along the ray: dx_j/dt.
    const Eigen::Vector2d dx_dt = pixel_from_local * ray_dir.cast<double>();
    const float db_dt = db_dx * float(dx_dt.x()) + db_dy * float(dx_dt.y());
    out.b[p] = top + fy * (bottom - top);
    out.db_dn[p] = db_dt / cos_ray;
    out.valid[p] = 1;
  }
}

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
                            vi.hit_map.hits.data(),
                            have_cos ? vi.hit_map.ray_cos.data() : nullptr,
                            &face_normals,
                            vj.hit_map.faces.data(),
                            vj.hit_map.points.data(),
                            float(options.visibility_tolerance_m * options.visibility_tolerance_m),
                            float(options.min_ray_cos),
                            ws};
#pragma omp parallel for schedule(dynamic, 8)
  for (int row = 0; row < h; ++row) WarpRow(context, row);
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
