#pragma once
// SATMESH_AVX2_CLONE: compile a hot function twice, for AVX2 and for baseline x86-64,
// and pick the copy at load time (GCC target_clones). The build has no -march, so the
// binary runs on any x86-64 and still gets wide SIMD where the CPU has it (AVX-512
// measured no faster for these loops; docs/benchmarks-history.md, session 3).
// clang 14 (the sanitizer/fuzz build) cannot clone function templates: one plain copy.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define SATMESH_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
#else
#define SATMESH_AVX2_CLONE
#endif
