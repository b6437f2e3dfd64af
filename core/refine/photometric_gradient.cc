#include "core/refine/photometric_gradient.h"

#include <cmath>

namespace satmesh {
namespace {

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
  const double tol2 = options.visibility_tolerance_m * options.visibility_tolerance_m;
  const int wj = vj.width(), hj = vj.height();

#pragma omp parallel for schedule(dynamic, 8)
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const size_t p = size_t(row) * w + col;
      const RayHit& hit = vi.hit_map.hits[p];
      if (!hit.hit()) continue;
      const Eigen::Vector3f& normal = face_normals[hit.face];
      const Eigen::Vector3f& ray_dir = vi.rays[p].direction;
      const float cos_ray = ray_dir.dot(normal);
      if (cos_ray > -float(options.min_ray_cos)) continue;  // grazing or back-facing
      const Eigen::Vector3f& X = vi.hit_map.points[p];
      Eigen::Matrix<double, 2, 3> pixel_from_local;
      const Eigen::Vector2d xj = vj.projection.PixelFromLocal(X.cast<double>(), &pixel_from_local);
      if (!(xj.x() >= 1.0 && xj.y() >= 1.0 && xj.x() < wj - 1.0 && xj.y() < hj - 1.0)) continue;
      // Visibility in j: j's own ray through that pixel must hit the same surface point.
      const size_t q = size_t(int(xj.y())) * wj + int(xj.x());
      const RayHit& hit_j = vj.hit_map.hits[q];
      if (!hit_j.hit()) continue;
      if (hit_j.face != hit.face && (vj.hit_map.points[q] - X).squaredNorm() > tol2) continue;
      float b, db_dx, db_dy;
      if (!SampleBilinearWithGradient(vj.image, xj.x(), xj.y(), &b, &db_dx, &db_dy)) continue;
      // DΠ_j in the local frame (the lattice holds the chain rule through the frame).
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

PairEnergy AccumulatePhotometricGradient(const ViewLevel& view_i, const ViewLevel& view_j,
                                         const TriangleMesh& mesh,
                                         const std::vector<Eigen::Vector3f>& face_normals,
                                         const PhotometricOptions& options,
                                         std::vector<Eigen::Vector3d>* vertex_gradient,
                                         std::vector<uint8_t>* touched,
                                         PairWorkspace* workspace) {
  PairWorkspace local;
  PairWorkspace& warp = workspace ? *workspace : local;
  WarpIntoView(view_i, view_j, face_normals, options, &warp);
  const int w = view_i.width(), h = view_i.height();
  const ZnccField field =
      ComputeZnccField(warp.a, warp.b, warp.valid, w, h, options.zncc, &warp.zncc);

  PairEnergy energy;
  energy.sum_zncc = field.sum_zncc;
  energy.num_windows = field.num_windows;
  if (!vertex_gradient && !touched) return energy;
  for (size_t p = 0; p < warp.valid.size(); ++p) {
    if (!warp.valid[p]) continue;
    ++energy.num_valid_pixels;
    const RayHit& hit = view_i.hit_map.hits[p];
    const Eigen::Vector3i& face = mesh.faces[hit.face];
    if (touched) (*touched)[face[0]] = (*touched)[face[1]] = (*touched)[face[2]] = 1;
    if (!vertex_gradient) continue;
    // ∂b/∂V_k = db_dn · w_k · n^T (ray-triangle intersection moved by vertex k).
    const double g = double(field.dM_db[p]) * warp.db_dn[p];
    if (g == 0) continue;
    const Eigen::Vector3d gn = g * face_normals[hit.face].cast<double>();
    (*vertex_gradient)[face[0]] += (1.0 - hit.u - hit.v) * gn;
    (*vertex_gradient)[face[1]] += double(hit.u) * gn;
    (*vertex_gradient)[face[2]] += double(hit.v) * gn;
  }
  return energy;
}

}  // namespace satmesh
