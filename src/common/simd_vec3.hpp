// simd_vec3.hpp — eight Eigen::Vector3f (24 contiguous floats) to and from
// their x, y and z lanes, for the AVX2 variants of loops over point and
// normal images (see cpu_features.hpp for the rules those variants follow).
#pragma once

#include "common/cpu_features.hpp"

#if defined(FINDMUG_AVX2_DISPATCH)
namespace findmug::detail {

// p[0..23] = x0 y0 z0 x1 ... z7 -> x = x0..x7, y = y0..y7, z = z0..z7.
__attribute__((target("avx2"))) inline void loadVec3x8(const float* p, __m256& x, __m256& y,
                                                      __m256& z) {
  __m256 m03 = _mm256_castps128_ps256(_mm_loadu_ps(p));      // x0 y0 z0 x1
  __m256 m14 = _mm256_castps128_ps256(_mm_loadu_ps(p + 4));  // y1 z1 x2 y2
  __m256 m25 = _mm256_castps128_ps256(_mm_loadu_ps(p + 8));  // z2 x3 y3 z3
  m03 = _mm256_insertf128_ps(m03, _mm_loadu_ps(p + 12), 1);  // x4 y4 z4 x5
  m14 = _mm256_insertf128_ps(m14, _mm_loadu_ps(p + 16), 1);  // y5 z5 x6 y6
  m25 = _mm256_insertf128_ps(m25, _mm_loadu_ps(p + 20), 1);  // z6 x7 y7 z7
  const __m256 xy = _mm256_shuffle_ps(m14, m25, _MM_SHUFFLE(2, 1, 3, 2));  // x2 y2 x3 y3
  const __m256 yz = _mm256_shuffle_ps(m03, m14, _MM_SHUFFLE(1, 0, 2, 1));  // y0 z0 y1 z1
  x = _mm256_shuffle_ps(m03, xy, _MM_SHUFFLE(2, 0, 3, 0));
  y = _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0));
  z = _mm256_shuffle_ps(yz, m25, _MM_SHUFFLE(3, 0, 3, 1));
}

// The inverse of loadVec3x8: x, y, z lanes -> p[0..23].
__attribute__((target("avx2"))) inline void storeVec3x8(float* p, __m256 x, __m256 y, __m256 z) {
  const __m256 rxy = _mm256_shuffle_ps(x, y, _MM_SHUFFLE(2, 0, 2, 0));  // x0 x2 y0 y2
  const __m256 ryz = _mm256_shuffle_ps(y, z, _MM_SHUFFLE(3, 1, 3, 1));  // y1 y3 z1 z3
  const __m256 rzx = _mm256_shuffle_ps(z, x, _MM_SHUFFLE(3, 1, 2, 0));  // z0 z2 x1 x3
  const __m256 r03 = _mm256_shuffle_ps(rxy, rzx, _MM_SHUFFLE(2, 0, 2, 0));  // x0 y0 z0 x1
  const __m256 r14 = _mm256_shuffle_ps(ryz, rxy, _MM_SHUFFLE(3, 1, 2, 0));  // y1 z1 x2 y2
  const __m256 r25 = _mm256_shuffle_ps(rzx, ryz, _MM_SHUFFLE(3, 1, 3, 1));  // z2 x3 y3 z3
  _mm_storeu_ps(p, _mm256_castps256_ps128(r03));
  _mm_storeu_ps(p + 4, _mm256_castps256_ps128(r14));
  _mm_storeu_ps(p + 8, _mm256_castps256_ps128(r25));
  _mm_storeu_ps(p + 12, _mm256_extractf128_ps(r03, 1));
  _mm_storeu_ps(p + 16, _mm256_extractf128_ps(r14, 1));
  _mm_storeu_ps(p + 20, _mm256_extractf128_ps(r25, 1));
}

// Eigen's dot of three, a0 b0 + (a1 b1 + a2 b2), on eight lanes (no FMA).
__attribute__((target("avx2"))) inline __m256 dot3x8(__m256 a0, __m256 a1, __m256 a2, __m256 b0,
                                                    __m256 b1, __m256 b2) {
  return _mm256_add_ps(_mm256_mul_ps(a0, b0),
                       _mm256_add_ps(_mm256_mul_ps(a1, b1), _mm256_mul_ps(a2, b2)));
}

}  // namespace findmug::detail
#endif
