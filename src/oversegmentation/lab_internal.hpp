// lab_internal.hpp — internal to findmug_core: the organized
// oversegmenter's table-driven sRGB -> CIELAB with its AVX2 path, and the
// switch the tests and benchmarks use to check that both paths give the
// same bits. Not installed.
#pragma once

#include <cstddef>

#include "findmug/cloud/cloud.hpp"

namespace findmug::detail {

enum class LabSimd {
  Auto,  // AVX2 where the CPU has it (what the Segmenter runs)
  Off,   // the scalar code only
};

// Tables clamped to [0, 1], |error| < 0.01 against the exact formula:
// colors[pixel[j]] into l[j], a[j], b[j] for j < count.
void labFromRgb(const Rgb8* colors, const int* pixel, std::size_t count, float* l, float* a,
                float* b, LabSimd simd);

}  // namespace findmug::detail
