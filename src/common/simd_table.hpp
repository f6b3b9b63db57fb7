// simd_table.hpp — linear interpolation in a float table, eight lanes at a
// time, for the AVX2 variants of the CIELAB conversions (see
// cpu_features.hpp for the rules those variants follow).
#pragma once

#include <cstddef>

#include "common/cpu_features.hpp"

namespace findmug::detail {

// table[k] + w * (table[k + 1] - table[k]) needs two table entries per
// lookup; stored as pairs (table[k], table[k + 1] - table[k]), one 8-byte
// gather reads both. The difference is the float subtraction the scalar
// code does, so the result is the same bits. Fills steps[0 .. 2 * entries).
inline void fillInterpolationSteps(const float* table, std::size_t entries, float* steps) {
  for (std::size_t k = 0; k < entries; ++k) {
    steps[2 * k] = table[k];
    steps[2 * k + 1] = table[k + 1] - table[k];
  }
}

#if defined(FINDMUG_AVX2_DISPATCH)
// Per lane table[k] + w * (table[k + 1] - table[k]), from the pairs of
// fillInterpolationSteps (8-byte aligned). Two gathers of four 8-byte pairs
// read half the elements of the two 4-byte gathers of table[k] and
// table[k + 1].
__attribute__((target("avx2"))) inline __m256 interpolate8(const float* steps, __m256i k,
                                                          __m256 w) {
  const double* pairs = reinterpret_cast<const double*>(steps);
  // The masked form: GCC 12 warns of the plain one's undefined source.
  const __m256d none = _mm256_setzero_pd(), all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  const __m256 lo = _mm256_castpd_ps(_mm256_mask_i32gather_pd(
      none, pairs, _mm256_castsi256_si128(k), all, 8));  // f0 d0 f1 d1 | f2 d2 f3 d3
  const __m256 hi = _mm256_castpd_ps(_mm256_mask_i32gather_pd(
      none, pairs, _mm256_extracti128_si256(k, 1), all, 8));  // f4 d4 f5 d5 | f6 d6 f7 d7
  // f0 f1 f4 f5 | f2 f3 f6 f7 -> f0 .. f7 (64-bit lanes 0 2 1 3), and the same for d.
  const __m256 f = _mm256_castpd_ps(_mm256_permute4x64_pd(
      _mm256_castps_pd(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(2, 0, 2, 0))), 0xD8));
  const __m256 d = _mm256_castpd_ps(_mm256_permute4x64_pd(
      _mm256_castps_pd(_mm256_shuffle_ps(lo, hi, _MM_SHUFFLE(3, 1, 3, 1))), 0xD8));
  return _mm256_add_ps(f, _mm256_mul_ps(w, d));
}
#endif

}  // namespace findmug::detail
