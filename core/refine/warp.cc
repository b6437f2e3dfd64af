#include "core/refine/warp.h"

#include <cstring>

#include "core/common/simd.h"
#include "core/refine/lattice_avx2.h"

namespace satmesh {
namespace {

// The scalar reference for one pixel p = (row, col) of view i.
inline void WarpPixel(const WarpContext& c, size_t p) {
  const ViewLevel& vi = *c.vi;
  const ViewLevel& vj = *c.vj;
  const SurfacePoint& hit = vi.hit_map.surface[p];
  const int face = hit.face;
  if (face < 0) return;
  const Eigen::Vector3f& ray_dir = vi.ray_directions[p];
  const float cos_ray = c.cos_i ? c.cos_i[p] : ray_dir.dot((*c.face_normals)[face]);
  if (cos_ray > -c.min_cos) return;  // grazing or back-facing
  const Eigen::Vector3f& X = hit.point;
  Eigen::Matrix<double, 2, 3> pixel_from_local;
  const Eigen::Vector2d xj = vj.projection.PixelFromLocal(X.cast<double>(), &pixel_from_local);
  const int wj = vj.width();
  if (!(xj.x() >= 1.0 && xj.y() >= 1.0 && xj.x() < wj - 1.0 && xj.y() < vj.height() - 1.0)) return;
  // Visibility in j: j's own ray through that pixel must hit the same surface point (the
  // same face needs no point read).
  const size_t q = size_t(int(xj.y())) * wj + int(xj.x());
  const SurfacePoint& hit_j = vj.hit_map.surface[q];
  if (hit_j.face != face && (hit_j.face < 0 || (hit_j.point - X).squaredNorm() > c.tol2)) return;
  // Bilinear sample of j (centre-origin coordinates, at least half a pixel inside) with
  // the exact derivatives of the interpolant.
  const double u = xj.x() - 0.5, v = xj.y() - 0.5;
  const int iu = int(u), iv = int(v);
  const float fx = float(u - iu), fy = float(v - iv);
  const float* s = vj.image.pixels.data() + size_t(iv) * wj + iu;
  const float p00 = s[0], p10 = s[1], p01 = s[wj], p11 = s[wj + 1];
  const float top = p00 + fx * (p10 - p00), bottom = p01 + fx * (p11 - p01);
  const float db_dx = (p10 - p00) + fy * ((p11 - p01) - (p10 - p00)), db_dy = bottom - top;
  // DΠ_j in the local frame along the ray: dx_j/dt.
  const Eigen::Vector2d dx_dt = pixel_from_local * ray_dir.cast<double>();
  const float db_dt = db_dx * float(dx_dt.x()) + db_dy * float(dx_dt.y());
  c.b[p] = top + fy * (bottom - top);
  c.db_dn[p] = db_dt / cos_ray;
  c.valid[p] = 1;
}

// (The AVX2 clone gets VEX code and roundsd for the lattice's floors.)
SATMESH_AVX2_CLONE
void WarpRowScalar(const WarpContext& c, int row, int col_begin, int col_end) {
  const size_t base = size_t(row) * c.vi->width();
  for (int col = col_begin; col < col_end; ++col) WarpPixel(c, base + col);
}

#ifdef SATMESH_HAVE_AVX2_LATTICE

// One row of view i, 8 pixels at a time.
struct RowWarpAvx2 {
  const WarpContext& c;
  size_t base;  // first pixel of the row
  int wj;
  const float* surface_i;  // this row's SurfacePoints (4 floats a pixel)
  const float* cos_i;
  const float* rays_i;  // 3 floats a pixel (unit direction)
  const float* surface_j;
  const float* image_j;
  LatticeAvx2 lattice_j;

  SATMESH_AVX2 RowWarpAvx2(const WarpContext& context, int row)
      : c(context), lattice_j(context.vj->projection) {
    const ViewLevel& vi = *c.vi;
    const ViewLevel& vj = *c.vj;
    wj = vj.width();
    base = size_t(row) * vi.width();
    surface_i = vi.hit_map.surface[base].point.data();
    cos_i = c.cos_i + base;
    rays_i = vi.ray_directions[base].data();
    surface_j = vj.hit_map.surface.data()->point.data();
    image_j = vj.image.pixels.data();
  }

  // Starts loading the j data that the group two ahead will read: j's pixels move along
  // a line as i's do (the warp is locally affine), so they are extrapolated from this
  // group's first and last lanes. A wrong guess (at depth edges) costs a wasted load.
  SATMESH_AVX2 void PrefetchAhead(__m256i q, __m256 inside) const {
    int i[8];
    LaneIndices(q, inside, i);
    const int mask = _mm256_movemask_ps(inside);
    if ((mask & 0x81) != 0x81) return;
    const long ahead = long(i[7] - i[0]) * 16 / 7;
    const long n = long(c.vj->hit_map.surface.size());
    for (int k = 0; k < 8; ++k) {
      const long p = i[k] + ahead;
      if (p < wj || p >= n - wj) continue;
      __builtin_prefetch(surface_j + 4 * p);
      __builtin_prefetch(image_j + p);  // (the rows above and below: measured slower)
    }
  }

  // Pixels [col, col + 8): writes b, db_dn and valid of all 8. Returns the lanes (bits)
  // that fall outside j's lattice, for the scalar path.
  SATMESH_AVX2 int Group(int col) const {
    const __m256i minus1 = _mm256_set1_epi32(-1), wj_v = _mm256_set1_epi32(wj);
    const __m256 half = _mm256_set1_ps(0.5f), one = _mm256_set1_ps(1.f), zero = _mm256_setzero_ps();
    // Hit, facing the view.
    __m256 X[3], face_f;
    LoadRecords4(surface_i + 4 * size_t(col), &X[0], &X[1], &X[2], &face_f);
    const __m256i face = _mm256_castps_si256(face_f);
    const __m256 cos_ray = _mm256_loadu_ps(cos_i + col);
    const __m256 hit = _mm256_castsi256_ps(_mm256_cmpgt_epi32(face, minus1));
    const __m256 facing =
        _mm256_and_ps(hit, _mm256_cmp_ps(cos_ray, _mm256_set1_ps(-c.min_cos), _CMP_LE_OQ));
    if (_mm256_testz_ps(facing, facing)) return 0;
    // X, and its pixel in j.
    __m256 xj, yj, J[6];
    const __m256 in_lattice = lattice_j.Project(X, facing, &xj, &yj, J);
    const int outside = _mm256_movemask_ps(_mm256_andnot_ps(in_lattice, facing));
    if (_mm256_testz_ps(in_lattice, in_lattice)) return outside;
    const __m256 max_x = _mm256_set1_ps(float(wj - 1)),
                 max_y = _mm256_set1_ps(float(c.vj->height() - 1));
    const __m256 inside = _mm256_and_ps(
        in_lattice, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(xj, one, _CMP_GE_OQ),
                                                _mm256_cmp_ps(yj, one, _CMP_GE_OQ)),
                                  _mm256_and_ps(_mm256_cmp_ps(xj, max_x, _CMP_LT_OQ),
                                                _mm256_cmp_ps(yj, max_y, _CMP_LT_OQ))));
    if (_mm256_testz_ps(inside, inside)) return outside;
    const __m256i q = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(yj), wj_v),
                                       _mm256_cvttps_epi32(xj));
    PrefetchAhead(q, inside);
    // Visibility in j: the same face, or j's point within the tolerance.
    __m256 Xj[3], face_j_f;
    GatherRecords4(surface_j, q, inside, &Xj[0], &Xj[1], &Xj[2], &face_j_f);
    const __m256i face_j =
        _mm256_blendv_epi8(minus1, _mm256_castps_si256(face_j_f), _mm256_castps_si256(inside));
    const __m256 same = _mm256_castsi256_ps(_mm256_cmpeq_epi32(face_j, face));
    const __m256 other = _mm256_andnot_ps(
        same, _mm256_and_ps(inside, _mm256_castsi256_ps(_mm256_cmpgt_epi32(face_j, minus1))));
    __m256 dist2 = zero;
    for (int a = 0; a < 3; ++a) {
      const __m256 diff = _mm256_sub_ps(Xj[a], X[a]);
      dist2 = _mm256_fmadd_ps(diff, diff, dist2);
    }
    const __m256 near =
        _mm256_and_ps(other, _mm256_cmp_ps(dist2, _mm256_set1_ps(c.tol2), _CMP_LE_OQ));
    const __m256 used = _mm256_and_ps(inside, _mm256_or_ps(same, near));
    const int used_bits = _mm256_movemask_ps(used);
    if (!used_bits) return outside;
    // Bilinear sample of j and the derivatives of the interpolant.
    const __m256 u = _mm256_sub_ps(xj, half), v = _mm256_sub_ps(yj, half);
    const __m256i iu = _mm256_cvttps_epi32(u), iv = _mm256_cvttps_epi32(v);
    const __m256 fx = _mm256_sub_ps(u, _mm256_cvtepi32_ps(iu));
    const __m256 fy = _mm256_sub_ps(v, _mm256_cvtepi32_ps(iv));
    const __m256i s = _mm256_add_epi32(_mm256_mullo_epi32(iv, wj_v), iu);
    const __m256i s_down = _mm256_add_epi32(s, wj_v);
    __m256 p00, p10, p01, p11;
    GatherPairs(image_j, s, used, &p00, &p10);
    GatherPairs(image_j, s_down, used, &p01, &p11);
    const __m256 dx_top = _mm256_sub_ps(p10, p00), dx_bottom = _mm256_sub_ps(p11, p01);
    const __m256 top = _mm256_fmadd_ps(fx, dx_top, p00);
    const __m256 bottom = _mm256_fmadd_ps(fx, dx_bottom, p01);
    const __m256 db_dx = _mm256_fmadd_ps(fy, _mm256_sub_ps(dx_bottom, dx_top), dx_top);
    const __m256 db_dy = _mm256_sub_ps(bottom, top);
    // DΠ_j along view i's ray.
    __m256 ray[3];
    LoadPoints3(rays_i + 3 * size_t(col), &ray[0], &ray[1], &ray[2]);
    const __m256 dx_dt =
        _mm256_fmadd_ps(J[2], ray[2], _mm256_fmadd_ps(J[1], ray[1], _mm256_mul_ps(J[0], ray[0])));
    const __m256 dy_dt =
        _mm256_fmadd_ps(J[5], ray[2], _mm256_fmadd_ps(J[4], ray[1], _mm256_mul_ps(J[3], ray[0])));
    const __m256 db_dt = _mm256_fmadd_ps(db_dx, dx_dt, _mm256_mul_ps(db_dy, dy_dt));
    const __m256 b = _mm256_fmadd_ps(fy, db_dy, top);
    const __m256 db_dn = _mm256_div_ps(db_dt, _mm256_blendv_ps(one, cos_ray, used));
    _mm256_storeu_ps(c.b + base + col, _mm256_and_ps(b, used));
    _mm256_storeu_ps(c.db_dn + base + col, _mm256_and_ps(db_dn, used));
    const uint64_t bytes = _pdep_u64(uint64_t(used_bits), 0x0101010101010101ULL);
    std::memcpy(c.valid + base + col, &bytes, 8);
    return outside;
  }
};

// 8 pixels at a time; returns the first column left for the scalar path (the last < 8).
SATMESH_AVX2 int WarpRowAvx2(const WarpContext& c, int row) {
  const RowWarpAvx2 warp(c, row);
  const int width = c.vi->width();
  int col = 0;
  for (; col + 8 <= width; col += 8) {
    int outside = warp.Group(col);
    for (; outside; outside &= outside - 1) WarpPixel(c, warp.base + col + __builtin_ctz(outside));
  }
  return col;
}

#endif  // SATMESH_HAVE_AVX2_LATTICE

}  // namespace

bool WarpHasAvx2() { return HasAvx2Lattice(); }

void WarpRow(const WarpContext& c, int row, bool vectorized) {
  int col = 0;
  const int width = c.vi->width();
#ifdef SATMESH_HAVE_AVX2_LATTICE
  if (vectorized && c.cos_i && WarpHasAvx2()) col = WarpRowAvx2(c, row);
#endif
  WarpRowScalar(c, row, col, width);
}

}  // namespace satmesh
