// lab.cpp — the organized oversegmenter's sRGB -> CIELAB (lab_internal.hpp): lookup
// tables with linear interpolation, and the same arithmetic eight colours at a time with
// AVX2 where the CPU has it.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "common/cpu_features.hpp"
#include "common/simd_table.hpp"
#include "oversegmentation/lab_internal.hpp"

namespace findmug::detail {
namespace {

// sRGB (D65) -> CIELAB with tables: a 256-entry sRGB -> linear table and a
// table of the CIELAB f(t) (cube root above the knee) with linear
// interpolation, |error| < 0.01 in L*, a*, b*. std::cbrt per pixel would
// cost more than the whole clustering.
class LabConverter {
 public:
  LabConverter() {
    for (int v = 0; v < 256; ++v) {
      const double c = v / 255.0;
      linear_[v] =
          static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
    }
    for (int i = 0; i <= kFSize; ++i) {
      const double t = static_cast<double>(i) * kFMax / kFSize;
      constexpr double kDelta = 6.0 / 29.0;
      f_[i] = static_cast<float>(
          t > kDelta * kDelta * kDelta ? std::cbrt(t) : t / (3 * kDelta * kDelta) + 4.0 / 29.0);
    }
    f_[kFSize + 1] = f_[kFSize];
    detail::fillInterpolationSteps(f_.data(), kFSize + 1, f_step_.data());
  }

  // convert() of colors[pixel[j]] into l[j], a[j], b[j] for j < count.
  void convertBatch(const Rgb8* colors, const int* pixel, std::size_t count, float* l, float* a,
                    float* b, detail::LabSimd simd) const {
    std::size_t j = 0;
#if defined(FINDMUG_AVX2_DISPATCH)
    if (simd == detail::LabSimd::Auto && detail::cpuHasAvx2()) {
      j = convertBatchAvx2(colors, pixel, count, l, a, b);
    }
#else
    (void)simd;
#endif
    for (; j < count; ++j) convert(colors[pixel[j]], l[j], a[j], b[j]);
  }

  void convert(const Rgb8& rgb, float& l, float& a, float& b) const {
    const float r = linear_[rgb.r];
    const float g = linear_[rgb.g];
    const float bl = linear_[rgb.b];
    // Linear sRGB -> XYZ, each row divided by the D65 white point.
    const float x = (0.4124564f * r + 0.3575761f * g + 0.1804375f * bl) * (1.0f / 0.95047f);
    const float y = 0.2126729f * r + 0.7151522f * g + 0.0721750f * bl;
    const float z = (0.0193339f * r + 0.1191920f * g + 0.9503041f * bl) * (1.0f / 1.08883f);
    const float fx = f(x);
    const float fy = f(y);
    const float fz = f(z);
    l = 116.0f * fy - 16.0f;
    a = 500.0f * (fx - fy);
    b = 200.0f * (fy - fz);
  }

 private:
  static constexpr int kFSize = 4096;
  static constexpr float kFMax = 1.0f;  // t = X/Xn etc. never exceeds 1 (+ rounding) for sRGB

  float f(float t) const {
    const float pos = std::clamp(t, 0.0f, kFMax) * (kFSize / kFMax);
    const int i = static_cast<int>(pos);
    const float frac = pos - static_cast<float>(i);
    return f_[i] + frac * (f_[i + 1] - f_[i]);
  }

#if defined(FINDMUG_AVX2_DISPATCH)
  // convert() eight colours at a time, with the same IEEE operations in the
  // same order (no FMA), so the same bits; the tables are read by gathers.
  // Returns how many it converted (a multiple of 8); the caller does the rest.
  __attribute__((target("avx2"))) std::size_t convertBatchAvx2(const Rgb8* colors, const int* pixel,
                                                               std::size_t count, float* l,
                                                               float* a, float* b) const {
    const __m256 one = _mm256_set1_ps(1.0f);
    std::size_t j = 0;
    for (; j + 8 <= count; j += 8) {
      alignas(32) int red[8], green[8], blue[8];
      for (int k = 0; k < 8; ++k) {
        const Rgb8& c = colors[pixel[j + k]];
        red[k] = c.r;
        green[k] = c.g;
        blue[k] = c.b;
      }
      const __m256 r = linearAvx2(red), g = linearAvx2(green), bl = linearAvx2(blue);
      const __m256 x = _mm256_mul_ps(rowAvx2(r, g, bl, 0.4124564f, 0.3575761f, 0.1804375f),
                                     _mm256_set1_ps(1.0f / 0.95047f));
      const __m256 y = rowAvx2(r, g, bl, 0.2126729f, 0.7151522f, 0.0721750f);
      const __m256 z = _mm256_mul_ps(rowAvx2(r, g, bl, 0.0193339f, 0.1191920f, 0.9503041f),
                                     _mm256_set1_ps(1.0f / 1.08883f));
      const __m256 fx = fAvx2(x, one), fy = fAvx2(y, one), fz = fAvx2(z, one);
      _mm256_storeu_ps(
          l + j, _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(116.0f), fy), _mm256_set1_ps(16.0f)));
      _mm256_storeu_ps(a + j, _mm256_mul_ps(_mm256_set1_ps(500.0f), _mm256_sub_ps(fx, fy)));
      _mm256_storeu_ps(b + j, _mm256_mul_ps(_mm256_set1_ps(200.0f), _mm256_sub_ps(fy, fz)));
    }
    return j;
  }

  // Helpers are member functions, not lambdas: a lambda in an avx2 function
  // is compiled for the base target.
  __attribute__((target("avx2"))) __m256 linearAvx2(const int* v) const {
    return _mm256_i32gather_ps(linear_.data(),
                               _mm256_load_si256(reinterpret_cast<const __m256i*>(v)), 4);
  }
  // cr * r + cg * g + cb * bl, in convert()'s order.
  __attribute__((target("avx2"))) static __m256 rowAvx2(__m256 r, __m256 g, __m256 bl, float cr,
                                                        float cg, float cb) {
    return _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(cr), r), _mm256_mul_ps(_mm256_set1_ps(cg), g)),
        _mm256_mul_ps(_mm256_set1_ps(cb), bl));
  }

  // f() on eight lanes. max/min stand for std::clamp: they differ only for
  // t = -0 (clamp keeps -0, max gives +0), and both give f_[0] then.
  __attribute__((target("avx2"))) __m256 fAvx2(__m256 t, __m256 one) const {
    static_assert(kFMax == 1.0f, "the clamp below is to [0, 1]");
    const __m256 pos = _mm256_mul_ps(_mm256_min_ps(_mm256_max_ps(t, _mm256_setzero_ps()), one),
                                     _mm256_set1_ps(kFSize / kFMax));
    const __m256i i = _mm256_cvttps_epi32(pos);
    const __m256 frac = _mm256_sub_ps(pos, _mm256_cvtepi32_ps(i));
    return detail::interpolate8(f_step_.data(), i, frac);
  }
#endif

  std::array<float, 256> linear_{};
  std::array<float, kFSize + 2> f_{};
  // (f_[i], f_[i + 1] - f_[i]) for i <= kFSize, for fAvx2 (simd_table.hpp).
  alignas(8) std::array<float, 2 * (kFSize + 1)> f_step_{};
};

const LabConverter& labConverter() {
  static const LabConverter converter;
  return converter;
}

}  // namespace

void labFromRgb(const Rgb8* colors, const int* pixel, std::size_t count, float* l, float* a,
                float* b, LabSimd simd) {
  labConverter().convertBatch(colors, pixel, count, l, a, b, simd);
}

}  // namespace findmug::detail
