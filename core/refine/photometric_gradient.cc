#include "core/refine/photometric_gradient.h"

#include <algorithm>
#include <cmath>

namespace satmesh {
namespace {

// Bilinear sample of an image at GDAL pixel coordinates (x, y) known to lie at least
// half a pixel inside the image, with the exact derivatives of the interpolant.
inline void SampleInside(const ImageF& image, double x, double y, float* value, float* d_dx,
                         float* d_dy) {
  const double u = x - 0.5, v = y - 0.5;  // centre-origin coordinates
  const int i = int(u), j = int(v);
  const float fx = float(u - i), fy = float(v - j);
  const float* p = &image.pixels[size_t(j) * image.width + i];
  const float p00 = p[0], p10 = p[1], p01 = p[image.width], p11 = p[image.width + 1];
  const float top = p00 + fx * (p10 - p00), bottom = p01 + fx * (p11 - p01);
  *value = top + fy * (bottom - top);
  *d_dx = (p10 - p00) + fy * ((p11 - p01) - (p10 - p00));
  *d_dy = bottom - top;
}

// Projects view i's hit points into j, tests visibility, samples j. Per pixel: a, b,
// valid, and db_dn = ∂b per unit move of the face along its normal.
void WarpIntoView(const ViewLevel& vi, const ViewLevel& vj,
                  const std::vector<Eigen::Vector3f>& face_normals,
                  const PhotometricOptions& options, PairWorkspace* ws) {
  const int w = vi.width(), h = vi.height();
  const size_t n = size_t(w) * h;
  PairWorkspace& warp = *ws;
  warp.a.resize(n);  // read only where valid
  warp.b.resize(n);
  warp.db_dn.resize(n);
  warp.valid.assign(n, 0);
  const float tol2 = float(options.visibility_tolerance_m * options.visibility_tolerance_m);
  const float min_cos = float(options.min_ray_cos);
  const int wj = vj.width(), hj = vj.height();
  const RayHit* hits_i = vi.hit_map.hits.data();
  const int* faces_j = vj.hit_map.faces.data();
  const bool have_cos = vi.hit_map.ray_cos.size() == n;  // else computed here

#pragma omp parallel for schedule(dynamic, 8)
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const size_t p = size_t(row) * w + col;
      const RayHit& hit = hits_i[p];
      if (!hit.hit()) continue;
      const Eigen::Vector3f& ray_dir = vi.rays[p].direction;
      const float cos_ray =
          have_cos ? vi.hit_map.ray_cos[p] : ray_dir.dot(face_normals[hit.face]);
      if (cos_ray > -min_cos) continue;  // grazing or back-facing
      const Eigen::Vector3f& X = vi.hit_map.points[p];
      Eigen::Matrix<double, 2, 3> pixel_from_local;
      const Eigen::Vector2d xj = vj.projection.PixelFromLocal(X.cast<double>(), &pixel_from_local);
      if (!(xj.x() >= 1.0 && xj.y() >= 1.0 && xj.x() < wj - 1.0 && xj.y() < hj - 1.0)) continue;
      // Visibility in j: j's own ray through that pixel must hit the same surface point.
      const size_t q = size_t(int(xj.y())) * wj + int(xj.x());
      const int face_j = faces_j[q];
      if (face_j < 0) continue;
      if (face_j != hit.face && (vj.hit_map.points[q] - X).squaredNorm() > tol2) continue;
      float b, db_dx, db_dy;
      SampleInside(vj.image, xj.x(), xj.y(), &b, &db_dx, &db_dy);
      // DΠ_j in the local frame (the projection holds the chain rule through the frame).
      const Eigen::Vector2d dx_dt = pixel_from_local * ray_dir.cast<double>();
      const double db_dt = db_dx * dx_dt.x() + db_dy * dx_dt.y();
      warp.a[p] = vi.image.pixels[p];
      warp.b[p] = b;
      warp.db_dn[p] = float(db_dt / cos_ray);
      warp.valid[p] = 1;
    }
  }
}

}  // namespace

void GradientAccumulator::Reset(size_t num_faces, size_t num_vertices) {
  face_weights_.assign(num_faces, Eigen::Vector3f::Zero());
  face_stamp_.assign(num_faces, 0);
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
      if (face_stamp_[f] == 0) continue;  // no pixel
      const Eigen::Vector3d normal = face_normals[f].cast<double>();
      const Eigen::Vector3i& face = mesh.faces[f];
      for (int k = 0; k < 3; ++k) (*vertex_gradient)[face[k]] += double(face_weights_[f][k]) * normal;
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
  const ZnccField field = ComputeZnccField(warp.a, warp.b, warp.valid, view_i.width(),
                                           view_i.height(), options.zncc, &warp.zncc);
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
