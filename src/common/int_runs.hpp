// int_runs.hpp — internal to findmug_core: where a run of equal ints ends,
// for the passes that walk a segment image run by run (connectivity,
// finalisation). Not installed.
#pragma once

#include <cstddef>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace findmug::detail {

// The first index in (begin, end) whose value differs from values[begin],
// or end; begin < end. Eight values per step with SSE2: segments cross a
// row in runs of tens of pixels, and one compare per pixel cost a loop
// iteration each.
inline std::size_t intRunEnd(const int* values, std::size_t begin, std::size_t end) {
  const int v = values[begin];
  std::size_t i = begin + 1;
#if defined(__SSE2__)
  const __m128i value = _mm_set1_epi32(v);
  for (; i + 8 <= end; i += 8) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(values + i));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(values + i + 4));
    const int same = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(a, value))) |
                     (_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(b, value))) << 4);
    if (same != 0xff) return i + static_cast<std::size_t>(__builtin_ctz(~same & 0xff));
  }
#endif
  while (i < end && values[i] == v) ++i;
  return i;
}

}  // namespace findmug::detail
