#include "core/refine/warp.h"

#include <cstring>

#include "core/common/simd.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define SATMESH_HAVE_AVX2_WARP 1
#endif

namespace satmesh {
namespace {

// The scalar reference for one pixel p = (row, col) of view i.
inline void WarpPixel(const WarpContext& c, size_t p) {
  const ViewLevel& vi = *c.vi;
  const ViewLevel& vj = *c.vj;
  const int face = vi.hit_map.faces[p];
  if (face < 0) return;
  const Eigen::Vector3f& ray_dir = vi.ray_directions[p];
  const float cos_ray = c.cos_i ? c.cos_i[p] : ray_dir.dot((*c.face_normals)[face]);
  if (cos_ray > -c.min_cos) return;  // grazing or back-facing
  const Eigen::Vector3f& X = vi.hit_map.points[p];
  Eigen::Matrix<double, 2, 3> pixel_from_local;
  const Eigen::Vector2d xj = vj.projection.PixelFromLocal(X.cast<double>(), &pixel_from_local);
  const int wj = vj.width();
  if (!(xj.x() >= 1.0 && xj.y() >= 1.0 && xj.x() < wj - 1.0 && xj.y() < vj.height() - 1.0)) return;
  // Visibility in j: j's own ray through that pixel must hit the same surface point (the
  // same face needs no point read).
  const size_t q = size_t(int(xj.y())) * wj + int(xj.x());
  const int face_j = vj.hit_map.faces[q];
  if (face_j != face && (face_j < 0 || (vj.hit_map.points[q] - X).squaredNorm() > c.tol2)) return;
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

#ifdef SATMESH_HAVE_AVX2_WARP

#define SATMESH_AVX2 __attribute__((target("avx2,fma,bmi2")))

// Lane loads without vgatherdps: with the gather-data-sampling microcode (Skylake to
// Ice Lake servers, this project's benchmark machine) one 8-lane gather costs ~28 cycles,
// 8 scalar loads and inserts ~10 (BENCHMARKS.md, session 5). Lanes off the mask read
// base[0] and give 0.
SATMESH_AVX2 inline void LaneIndices(__m256i index, __m256 mask, int* out) {
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out),
                      _mm256_and_si256(index, _mm256_castps_si256(mask)));
}
SATMESH_AVX2 inline __m256 Gather(const float* base, __m256i index, __m256 mask) {
  int i[8];
  LaneIndices(index, mask, i);
  const __m256 v = _mm256_setr_ps(base[i[0]], base[i[1]], base[i[2]], base[i[3]], base[i[4]],
                                  base[i[5]], base[i[6]], base[i[7]]);
  return _mm256_and_ps(v, mask);
}
SATMESH_AVX2 inline __m256i GatherInt(const int* base, __m256i index, __m256i mask, __m256i fill) {
  int i[8];
  LaneIndices(index, _mm256_castsi256_ps(mask), i);
  const __m256i v = _mm256_setr_epi32(base[i[0]], base[i[1]], base[i[2]], base[i[3]], base[i[4]],
                                      base[i[5]], base[i[6]], base[i[7]]);
  return _mm256_blendv_epi8(fill, v, mask);
}

// x, y, z of 8 consecutive 3-float points (24 floats from p) as three vectors.
SATMESH_AVX2 inline void LoadPoints3(const float* p, __m256* x, __m256* y, __m256* z) {
  const __m256 m03 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p)), _mm_loadu_ps(p + 12), 1);
  const __m256 m14 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 4)), _mm_loadu_ps(p + 16), 1);
  const __m256 m25 = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 8)), _mm_loadu_ps(p + 20), 1);
  const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));
  const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));
  *x = _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0));
  *y = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
  *z = _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1));
}

// The 8 floats at base + 8 * index[k] for each lane k, transposed: out[m] holds float m of
// every lane's record (lanes off the mask read record 0).
SATMESH_AVX2 inline void GatherRecords8(const float* base, __m256i index, __m256 mask, __m256* out) {
  int i[8];
  LaneIndices(index, mask, i);
  __m256 r[8];
  for (int k = 0; k < 8; ++k) r[k] = _mm256_loadu_ps(base + 8 * size_t(i[k]));
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 s0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 s2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 s4 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s5 = _mm256_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
  const __m256 s6 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0));
  const __m256 s7 = _mm256_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2));
  out[0] = _mm256_permute2f128_ps(s0, s4, 0x20);
  out[1] = _mm256_permute2f128_ps(s1, s5, 0x20);
  out[2] = _mm256_permute2f128_ps(s2, s6, 0x20);
  out[3] = _mm256_permute2f128_ps(s3, s7, 0x20);
  out[4] = _mm256_permute2f128_ps(s0, s4, 0x31);
  out[5] = _mm256_permute2f128_ps(s1, s5, 0x31);
  out[6] = _mm256_permute2f128_ps(s2, s6, 0x31);
  out[7] = _mm256_permute2f128_ps(s3, s7, 0x31);
}

// The two adjacent floats at base + index[k] (and + 1) of each lane, as (first, second).
SATMESH_AVX2 inline void GatherPairs(const float* base, __m256i index, __m256 mask, __m256* first,
                                     __m256* second) {
  int i[8];
  LaneIndices(index, mask, i);
  auto pair = [&](__m128 v, int k, bool high) {
    const __m64* q = reinterpret_cast<const __m64*>(base + i[k]);
    return high ? _mm_loadh_pi(v, q) : _mm_loadl_pi(v, q);
  };
  const __m128 z = _mm_setzero_ps();
  const __m256 a = _mm256_set_m128(pair(pair(z, 4, false), 5, true), pair(pair(z, 0, false), 1, true));
  const __m256 b = _mm256_set_m128(pair(pair(z, 6, false), 7, true), pair(pair(z, 2, false), 3, true));
  *first = _mm256_and_ps(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)), mask);
  *second = _mm256_and_ps(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)), mask);
}

// One row of view i, 8 pixels at a time.
struct RowWarpAvx2 {
  const WarpContext& c;
  size_t base;              // first pixel of the row
  int wj;
  const float* cells;       // j's float lattice, 8 floats a cell
  const int* faces_i;       // this row's
  const float* cos_i;
  const float* points_i;    // 3 floats a pixel
  const float* rays_i;      // 3 floats a pixel (unit direction)
  const int* faces_j;
  const float* points_j;
  const float* image_j;
  __m256 origin[3], inv_spacing[3], spacing[3], n_cells[3];
  __m256i nx, ny;

  SATMESH_AVX2 RowWarpAvx2(const WarpContext& context, int row) : c(context) {
    const ViewLevel& vi = *c.vi;
    const ViewLevel& vj = *c.vj;
    wj = vj.width();
    base = size_t(row) * vi.width();
    const ProjectionGrid::FloatLattice lat = vj.projection.float_lattice();
    cells = &lat.cells[0].pixel[0];
    faces_i = vi.hit_map.faces.data() + base;
    cos_i = c.cos_i + base;
    points_i = vi.hit_map.points[base].data();
    rays_i = vi.ray_directions[base].data();
    faces_j = vj.hit_map.faces.data();
    points_j = vj.hit_map.points.data()->data();
    image_j = vj.image.pixels.data();
    for (int a = 0; a < 3; ++a) {
      origin[a] = _mm256_set1_ps(lat.origin[a]);
      inv_spacing[a] = _mm256_set1_ps(lat.inv_spacing[a]);
      spacing[a] = _mm256_set1_ps(lat.spacing[a]);
      n_cells[a] = _mm256_set1_ps(float(lat.n[a]));
    }
    nx = _mm256_set1_epi32(lat.n[0]);
    ny = _mm256_set1_epi32(lat.n[1]);
  }

  // Pixels [col, col + 8): writes b, db_dn and valid of all 8. Returns the lanes (bits)
  // that fall outside j's lattice, for the scalar path.
  SATMESH_AVX2 int Group(int col) const {
    const __m256i minus1 = _mm256_set1_epi32(-1), wj_v = _mm256_set1_epi32(wj);
    const __m256 half = _mm256_set1_ps(0.5f), one = _mm256_set1_ps(1.f), zero = _mm256_setzero_ps();
    // Hit, facing the view.
    const __m256i face = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(faces_i + col));
    const __m256 cos_ray = _mm256_loadu_ps(cos_i + col);
    const __m256 hit = _mm256_castsi256_ps(_mm256_cmpgt_epi32(face, minus1));
    const __m256 facing =
        _mm256_and_ps(hit, _mm256_cmp_ps(cos_ray, _mm256_set1_ps(-c.min_cos), _CMP_LE_OQ));
    if (_mm256_testz_ps(facing, facing)) return 0;
    // X, and its lattice cell in j.
    __m256 X[3], g[3], cell_f[3];
    __m256 in_lattice = facing;
    LoadPoints3(points_i + 3 * size_t(col), &X[0], &X[1], &X[2]);
    for (int a = 0; a < 3; ++a) {
      g[a] = _mm256_mul_ps(_mm256_sub_ps(X[a], origin[a]), inv_spacing[a]);
      cell_f[a] = _mm256_floor_ps(g[a]);
      in_lattice = _mm256_and_ps(in_lattice, _mm256_and_ps(_mm256_cmp_ps(g[a], zero, _CMP_GE_OQ),
                                                           _mm256_cmp_ps(g[a], n_cells[a], _CMP_LT_OQ)));
    }
    const int outside = _mm256_movemask_ps(_mm256_andnot_ps(in_lattice, facing));
    if (_mm256_testz_ps(in_lattice, in_lattice)) return outside;
    const __m256i cell = _mm256_add_epi32(
        _mm256_mullo_epi32(_mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(cell_f[2]), ny),
                                            _mm256_cvttps_epi32(cell_f[1])),
                           nx),
        _mm256_cvttps_epi32(cell_f[0]));
    __m256 d[3], record[8];
    for (int a = 0; a < 3; ++a)
      d[a] = _mm256_mul_ps(_mm256_sub_ps(g[a], _mm256_add_ps(cell_f[a], half)), spacing[a]);
    GatherRecords8(cells, cell, in_lattice, record);  // pixel (2), Jacobian (6)
    const __m256* J = record + 2;
    const __m256 xj = _mm256_fmadd_ps(J[2], d[2], _mm256_fmadd_ps(J[1], d[1],
                      _mm256_fmadd_ps(J[0], d[0], record[0])));
    const __m256 yj = _mm256_fmadd_ps(J[5], d[2], _mm256_fmadd_ps(J[4], d[1],
                      _mm256_fmadd_ps(J[3], d[0], record[1])));
    const __m256 max_x = _mm256_set1_ps(float(wj - 1)), max_y = _mm256_set1_ps(float(c.vj->height() - 1));
    const __m256 inside = _mm256_and_ps(
        in_lattice, _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(xj, one, _CMP_GE_OQ),
                                                _mm256_cmp_ps(yj, one, _CMP_GE_OQ)),
                                  _mm256_and_ps(_mm256_cmp_ps(xj, max_x, _CMP_LT_OQ),
                                                _mm256_cmp_ps(yj, max_y, _CMP_LT_OQ))));
    if (_mm256_testz_ps(inside, inside)) return outside;
    // Visibility in j: the same face, or j's point within the tolerance.
    const __m256i q = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(yj), wj_v),
                                       _mm256_cvttps_epi32(xj));
    const __m256i face_j = GatherInt(faces_j, q, _mm256_castps_si256(inside), minus1);
    const __m256 same = _mm256_castsi256_ps(_mm256_cmpeq_epi32(face_j, face));
    const __m256 other = _mm256_andnot_ps(
        same, _mm256_and_ps(inside, _mm256_castsi256_ps(_mm256_cmpgt_epi32(face_j, minus1))));
    const __m256i q3 = _mm256_add_epi32(q, _mm256_add_epi32(q, q));
    __m256 dist2 = zero;
    if (!_mm256_testz_ps(other, other)) {
      for (int a = 0; a < 3; ++a) {
        const __m256 diff = _mm256_sub_ps(Gather(points_j + a, q3, other), X[a]);
        dist2 = _mm256_fmadd_ps(diff, diff, dist2);
      }
    }
    const __m256 near = _mm256_and_ps(other, _mm256_cmp_ps(dist2, _mm256_set1_ps(c.tol2), _CMP_LE_OQ));
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

#endif  // SATMESH_HAVE_AVX2_WARP

}  // namespace

bool WarpHasAvx2() {
#ifdef SATMESH_HAVE_AVX2_WARP
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                          __builtin_cpu_supports("bmi2");
  return has;
#else
  return false;
#endif
}

void WarpRow(const WarpContext& c, int row, bool vectorized) {
  int col = 0;
  const int width = c.vi->width();
#ifdef SATMESH_HAVE_AVX2_WARP
  if (vectorized && c.cos_i && WarpHasAvx2()) col = WarpRowAvx2(c, row);
#endif
  WarpRowScalar(c, row, col, width);
}

}  // namespace satmesh
