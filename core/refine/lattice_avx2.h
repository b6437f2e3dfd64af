#pragma once
// AVX2 building blocks of the refinement's per-pixel loops (warp.cc, hit_map_raster.cc):
// loads of 8 lanes without vgatherdps, and the projection of 8 points through a view's
// float projection lattice (projection_grid.h). They exist where SATMESH_HAVE_AVX2_LATTICE
// is defined; each is compiled for AVX2/FMA/BMI2 and must only run where
// HasAvx2Lattice() is true.
namespace satmesh {

// True when this CPU runs the functions below (always false off x86-64 GCC/Clang).
inline bool HasAvx2Lattice() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                          __builtin_cpu_supports("bmi2");
  return has;
#else
  return false;
#endif
}

}  // namespace satmesh

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include <cstddef>

#include "core/refine/projection_grid.h"

#define SATMESH_HAVE_AVX2_LATTICE 1

namespace satmesh {

#define SATMESH_AVX2 __attribute__((target("avx2,fma,bmi2")))

// Lane loads without vgatherdps: with the gather-data-sampling microcode (Skylake to
// Ice Lake servers, this project's benchmark machine) one 8-lane gather costs ~28 cycles,
// 8 scalar loads and inserts ~10 (docs/benchmarks-history.md, session 5). Lanes off the mask read
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

// x, y, z of 8 consecutive 3-float points (24 floats from p) as three vectors.
SATMESH_AVX2 inline void LoadPoints3(const float* p, __m256* x, __m256* y, __m256* z) {
  const __m256 m03 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p)), _mm_loadu_ps(p + 12), 1);
  const __m256 m14 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 4)), _mm_loadu_ps(p + 16), 1);
  const __m256 m25 =
      _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(p + 8)), _mm_loadu_ps(p + 20), 1);
  const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));
  const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));
  *x = _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0));
  *y = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
  *z = _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1));
}

// a_k holds 4-float records k (low half) and k + 4 (high half); f_m gets field m of the
// 8 records, in lane order. Its own inverse (fields in, records out).
SATMESH_AVX2 inline void Transpose4(__m256 a0, __m256 a1, __m256 a2, __m256 a3, __m256* f0,
                                    __m256* f1, __m256* f2, __m256* f3) {
  const __m256 t0 = _mm256_unpacklo_ps(a0, a1), t1 = _mm256_unpackhi_ps(a0, a1);
  const __m256 t2 = _mm256_unpacklo_ps(a2, a3), t3 = _mm256_unpackhi_ps(a2, a3);
  *f0 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  *f1 = _mm256_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  *f2 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  *f3 = _mm256_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

// The 4 floats at lo and at hi as one vector (lo in the low half).
SATMESH_AVX2 inline __m256 Load2x4(const float* lo, const float* hi) {
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(lo)), _mm_loadu_ps(hi), 1);
}

// Fields 0-3 of 8 consecutive 4-float records (32 floats from p).
SATMESH_AVX2 inline void LoadRecords4(const float* p, __m256* f0, __m256* f1, __m256* f2,
                                      __m256* f3) {
  Transpose4(Load2x4(p, p + 16), Load2x4(p + 4, p + 20), Load2x4(p + 8, p + 24),
             Load2x4(p + 12, p + 28), f0, f1, f2, f3);
}

// The inverse of LoadRecords4: fields 0-3 of 8 records into 32 floats from p.
SATMESH_AVX2 inline void StoreRecords4(__m256 f0, __m256 f1, __m256 f2, __m256 f3, float* p) {
  __m256 r[4];
  Transpose4(f0, f1, f2, f3, &r[0], &r[1], &r[2], &r[3]);
  for (int k = 0; k < 4; ++k) {
    _mm_storeu_ps(p + 4 * k, _mm256_castps256_ps128(r[k]));
    _mm_storeu_ps(p + 16 + 4 * k, _mm256_extractf128_ps(r[k], 1));
  }
}

// Fields 0-3 of the 4-float records base + 4 * index[k] (lanes off the mask read record
// 0 and give 0).
SATMESH_AVX2 inline void GatherRecords4(const float* base, __m256i index, __m256 mask, __m256* f0,
                                        __m256* f1, __m256* f2, __m256* f3) {
  int i[8];
  LaneIndices(index, mask, i);
  const float* r[8];
  for (int k = 0; k < 8; ++k) r[k] = base + 4 * size_t(i[k]);
  Transpose4(Load2x4(r[0], r[4]), Load2x4(r[1], r[5]), Load2x4(r[2], r[6]), Load2x4(r[3], r[7]), f0,
             f1, f2, f3);
  *f0 = _mm256_and_ps(*f0, mask);
  *f1 = _mm256_and_ps(*f1, mask);
  *f2 = _mm256_and_ps(*f2, mask);
  *f3 = _mm256_and_ps(*f3, mask);
}

// The 8 floats at base + 8 * index[k] for each lane k, transposed: out[m] holds float m of
// every lane's record (lanes off the mask read record 0).
SATMESH_AVX2 inline void GatherRecords8(const float* base, __m256i index, __m256 mask,
                                        __m256* out) {
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
  const __m256 a =
      _mm256_set_m128(pair(pair(z, 4, false), 5, true), pair(pair(z, 0, false), 1, true));
  const __m256 b =
      _mm256_set_m128(pair(pair(z, 6, false), 7, true), pair(pair(z, 2, false), 3, true));
  *first = _mm256_and_ps(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)), mask);
  *second = _mm256_and_ps(_mm256_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)), mask);
}

// A view's float projection lattice, broadcast for 8 lanes.
struct LatticeAvx2 {
  const float* cells;  // 8 floats a cell: pixel (2), Jacobian (6)
  __m256 origin[3], inv_spacing[3], spacing[3], n_cells[3];
  __m256i nx, ny;

  SATMESH_AVX2 explicit LatticeAvx2(const ProjectionGrid& grid) {
    const ProjectionGrid::FloatLattice lat = grid.float_lattice();
    cells = &lat.cells[0].pixel[0];
    for (int a = 0; a < 3; ++a) {
      origin[a] = _mm256_set1_ps(lat.origin[a]);
      inv_spacing[a] = _mm256_set1_ps(lat.inv_spacing[a]);
      spacing[a] = _mm256_set1_ps(lat.spacing[a]);
      n_cells[a] = _mm256_set1_ps(float(lat.n[a]));
    }
    nx = _mm256_set1_epi32(lat.n[0]);
    ny = _mm256_set1_epi32(lat.n[1]);
  }

  // Pixel (x, y) and Jacobian J (d(col,row)/d(x,y,z), row-major) of the lanes of X that
  // are on `mask` and inside the lattice; returns those lanes (the others need the exact
  // projection, ProjectionGrid::PixelFromLocal).
  SATMESH_AVX2 __m256 Project(const __m256 X[3], __m256 mask, __m256* x, __m256* y,
                              __m256 J[6]) const {
    const __m256 zero = _mm256_setzero_ps(), half = _mm256_set1_ps(0.5f);
    __m256 g[3], cell_f[3];
    __m256 in_lattice = mask;
    for (int a = 0; a < 3; ++a) {
      g[a] = _mm256_mul_ps(_mm256_sub_ps(X[a], origin[a]), inv_spacing[a]);
      cell_f[a] = _mm256_floor_ps(g[a]);
      in_lattice =
          _mm256_and_ps(in_lattice, _mm256_and_ps(_mm256_cmp_ps(g[a], zero, _CMP_GE_OQ),
                                                  _mm256_cmp_ps(g[a], n_cells[a], _CMP_LT_OQ)));
    }
    if (_mm256_testz_ps(in_lattice, in_lattice)) {
      *x = *y = zero;
      return in_lattice;
    }
    const __m256i cell = _mm256_add_epi32(
        _mm256_mullo_epi32(_mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(cell_f[2]), ny),
                                            _mm256_cvttps_epi32(cell_f[1])),
                           nx),
        _mm256_cvttps_epi32(cell_f[0]));
    __m256 d[3], record[8];
    for (int a = 0; a < 3; ++a)
      d[a] = _mm256_mul_ps(_mm256_sub_ps(g[a], _mm256_add_ps(cell_f[a], half)), spacing[a]);
    GatherRecords8(cells, cell, in_lattice, record);
    for (int k = 0; k < 6; ++k) J[k] = record[2 + k];
    *x = _mm256_fmadd_ps(J[2], d[2],
                         _mm256_fmadd_ps(J[1], d[1], _mm256_fmadd_ps(J[0], d[0], record[0])));
    *y = _mm256_fmadd_ps(J[5], d[2],
                         _mm256_fmadd_ps(J[4], d[1], _mm256_fmadd_ps(J[3], d[0], record[1])));
    return in_lattice;
  }
};

}  // namespace satmesh

#endif  // x86-64 GCC/Clang
