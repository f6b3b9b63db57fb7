// cpu_features.hpp — run-time choice of the AVX2 variants of hot loops.
//
// Where FINDMUG_AVX2_DISPATCH is defined (x86-64 with GCC or clang), a hot
// loop may have a `__attribute__((target("avx2")))` variant beside its
// portable one, taken when cpuHasAvx2(). Both must do the same IEEE
// operations in the same order (no FMA), so the CPU never changes a result.
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define FINDMUG_AVX2_DISPATCH 1

namespace findmug::detail {

// Asked once per process.
inline bool cpuHasAvx2() {
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
}

}  // namespace findmug::detail
#endif
