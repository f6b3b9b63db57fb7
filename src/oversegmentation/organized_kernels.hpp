// organized_kernels.hpp — internal to findmug_core: the organized oversegmenter's
// inner loops, SSE2 and AVX2 (window search, centre sums, the refinement's first test),
// inline here so that oversegmentation_organized.cpp, their one caller, compiles them
// into its loops. Each vector version does the scalar code's IEEE operations in the same
// order (no FMA), so every path gives the same bits. Not installed.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "common/cpu_features.hpp"
#include "common/simd_vec3.hpp"
#include "oversegmentation/organized_internal.hpp"

namespace findmug::detail::organized {

struct CentreSum {  // updateCentres: sums over a cluster's pixels
  std::array<double, kNumChannels> ch{};
  double u = 0, v = 0;
  int count = 0;
};

// For each pixel of rows [y0, y1) x columns [x0, x1): if it is nearer to the
// cluster centre than `best`, take it. (Portable SSE2 version; the AVX one
// below does the same arithmetic eight pixels at a time.)
inline void assignWindowSse(const FeatureGrid& g, const std::array<float, kNumChannels>& c,
                            const Weights& wt, int label, int x0, int x1, int y0, int y1,
                            float* best, int* labels) {
  const float* ch[kNumChannels];
  for (int k = 0; k < kNumChannels; ++k) ch[k] = g.ch[k].data();
  for (int y = y0; y < y1; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * g.width;
    int x = x0;
#if defined(__SSE2__)
    const __m128 cl = _mm_set1_ps(c[kL]), ca = _mm_set1_ps(c[kA]), cb = _mm_set1_ps(c[kB]);
    const __m128 cx = _mm_set1_ps(c[kX]), cy = _mm_set1_ps(c[kY]), cz = _mm_set1_ps(c[kZ]);
    const __m128 cnx = _mm_set1_ps(c[kNX]), cny = _mm_set1_ps(c[kNY]), cnz = _mm_set1_ps(c[kNZ]);
    const __m128 wc = _mm_set1_ps(wt.color), ws = _mm_set1_ps(wt.spatial),
                 wn = _mm_set1_ps(wt.normal);
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 one = _mm_set1_ps(1.0f);
    const __m128i lab = _mm_set1_epi32(label);
    for (; x + 4 <= x1; x += 4) {
      const std::size_t i = row + x;
      const __m128 dl = _mm_sub_ps(_mm_loadu_ps(ch[kL] + i), cl);
      const __m128 da = _mm_sub_ps(_mm_loadu_ps(ch[kA] + i), ca);
      const __m128 db = _mm_sub_ps(_mm_loadu_ps(ch[kB] + i), cb);
      const __m128 dx = _mm_sub_ps(_mm_loadu_ps(ch[kX] + i), cx);
      const __m128 dy = _mm_sub_ps(_mm_loadu_ps(ch[kY] + i), cy);
      const __m128 dz = _mm_sub_ps(_mm_loadu_ps(ch[kZ] + i), cz);
      const __m128 color2 =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(dl, dl), _mm_mul_ps(da, da)), _mm_mul_ps(db, db));
      const __m128 space2 =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      const __m128 dot = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(ch[kNX] + i), cnx),
                                               _mm_mul_ps(_mm_loadu_ps(ch[kNY] + i), cny)),
                                    _mm_mul_ps(_mm_loadu_ps(ch[kNZ] + i), cnz));
      const __m128 d = _mm_add_ps(
          _mm_add_ps(_mm_mul_ps(wc, _mm_sqrt_ps(color2)), _mm_mul_ps(ws, _mm_sqrt_ps(space2))),
          _mm_mul_ps(wn, _mm_sub_ps(one, _mm_and_ps(dot, abs_mask))));
      const __m128 old = _mm_loadu_ps(best + i);
      const __m128 closer = _mm_cmplt_ps(d, old);  // false for NaN (invalid pixels)
      _mm_storeu_ps(best + i, _mm_or_ps(_mm_and_ps(closer, d), _mm_andnot_ps(closer, old)));
      const __m128i mask = _mm_castps_si128(closer);
      const __m128i old_label = _mm_loadu_si128(reinterpret_cast<const __m128i*>(labels + i));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(labels + i),
                       _mm_or_si128(_mm_and_si128(mask, lab), _mm_andnot_si128(mask, old_label)));
    }
#endif
    for (; x < x1; ++x) {
      const std::size_t i = row + x;
      const float dl = ch[kL][i] - c[kL], da = ch[kA][i] - c[kA], db = ch[kB][i] - c[kB];
      const float dx = ch[kX][i] - c[kX], dy = ch[kY][i] - c[kY], dz = ch[kZ][i] - c[kZ];
      const float dot = ch[kNX][i] * c[kNX] + ch[kNY][i] * c[kNY] + ch[kNZ][i] * c[kNZ];
      const float d = wt.color * std::sqrt(dl * dl + da * da + db * db) +
                      wt.spatial * std::sqrt(dx * dx + dy * dy + dz * dz) +
                      wt.normal * (1.0f - std::fabs(dot));
      if (d < best[i]) {
        best[i] = d;
        labels[i] = label;
      }
    }
  }
}

#if defined(FINDMUG_AVX2_DISPATCH)
// assignWindowSse with 8-wide AVX registers. The same IEEE operations in the
// same order per pixel (no FMA: the target is "avx2", not "fma"), so the
// result is bit-identical to the SSE2 and scalar code; only the lane count
// differs. About 40 % of the oversegmenter's time is this loop.
__attribute__((target("avx2"))) inline void assignWindowAvx(
    const FeatureGrid& g, const std::array<float, kNumChannels>& c, const Weights& wt, int label,
    int x0, int x1, int y0, int y1, float* best, int* labels) {
  const float* ch[kNumChannels];
  for (int k = 0; k < kNumChannels; ++k) ch[k] = g.ch[k].data();
  const __m256 cl = _mm256_set1_ps(c[kL]), ca = _mm256_set1_ps(c[kA]), cb = _mm256_set1_ps(c[kB]);
  const __m256 cx = _mm256_set1_ps(c[kX]), cy = _mm256_set1_ps(c[kY]), cz = _mm256_set1_ps(c[kZ]);
  const __m256 cnx = _mm256_set1_ps(c[kNX]), cny = _mm256_set1_ps(c[kNY]),
               cnz = _mm256_set1_ps(c[kNZ]);
  const __m256 wc = _mm256_set1_ps(wt.color), ws = _mm256_set1_ps(wt.spatial),
               wn = _mm256_set1_ps(wt.normal);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 one = _mm256_set1_ps(1.0f);
  const __m256 lab = _mm256_castsi256_ps(_mm256_set1_epi32(label));
  const std::size_t grid_size = static_cast<std::size_t>(g.width) * g.height;
  const __m256i lane_index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int y = y0; y < y1; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * g.width;
    // A window row is 10-20 pixels wide: the last vector runs past x1 and
    // its extra lanes are masked off (they read pixels beyond the window,
    // inside the grid, and write back what they read), so no pixel takes the
    // scalar path except at the very end of the grid.
    for (int x = x0; x < x1; x += 8) {
      const std::size_t i = row + x;
      if (i + 8 > grid_size) {
        assignWindowSse(g, c, wt, label, x, x1, y, y + 1, best, labels);
        break;
      }
      const __m256 inside =
          _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(x1 - x), lane_index));
      const __m256 dl = _mm256_sub_ps(_mm256_loadu_ps(ch[kL] + i), cl);
      const __m256 da = _mm256_sub_ps(_mm256_loadu_ps(ch[kA] + i), ca);
      const __m256 db = _mm256_sub_ps(_mm256_loadu_ps(ch[kB] + i), cb);
      const __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(ch[kX] + i), cx);
      const __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(ch[kY] + i), cy);
      const __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(ch[kZ] + i), cz);
      const __m256 color2 = _mm256_add_ps(
          _mm256_add_ps(_mm256_mul_ps(dl, dl), _mm256_mul_ps(da, da)), _mm256_mul_ps(db, db));
      const __m256 space2 = _mm256_add_ps(
          _mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
      const __m256 dot =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_loadu_ps(ch[kNX] + i), cnx),
                                      _mm256_mul_ps(_mm256_loadu_ps(ch[kNY] + i), cny)),
                        _mm256_mul_ps(_mm256_loadu_ps(ch[kNZ] + i), cnz));
      const __m256 d =
          _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(wc, _mm256_sqrt_ps(color2)),
                                      _mm256_mul_ps(ws, _mm256_sqrt_ps(space2))),
                        _mm256_mul_ps(wn, _mm256_sub_ps(one, _mm256_and_ps(dot, abs_mask))));
      const __m256 old = _mm256_loadu_ps(best + i);
      // false for NaN (invalid pixels) and for lanes outside the window
      const __m256 closer = _mm256_and_ps(_mm256_cmp_ps(d, old, _CMP_LT_OQ), inside);
      _mm256_storeu_ps(best + i, _mm256_blendv_ps(old, d, closer));
      float* label_slot = reinterpret_cast<float*>(labels + i);
      _mm256_storeu_ps(label_slot, _mm256_blendv_ps(_mm256_loadu_ps(label_slot), lab, closer));
    }
  }
}

#endif

// updateCentres: the sum of the pixel columns x0 .. x1 - 1 of a run. Sums of
// integers far below 2^53 are exact in any order, so this is the sum pixel
// by pixel, to the bit.
inline double columnSum(int x0, int x1) {
  return static_cast<double>(static_cast<std::int64_t>(x0 + x1 - 1) * (x1 - x0) / 2);
}

// Adds the channels of pixels [x0, x1) of one row (starting at grid index
// row) to s.ch, one pixel after the other (updateCentres).
inline void addRunChannels(const float* const* ch, std::size_t row, int x0, int x1, CentreSum& s) {
  double l = s.ch[kL], a = s.ch[kA], b = s.ch[kB];
  double px = s.ch[kX], py = s.ch[kY], pz = s.ch[kZ];
  double nx = s.ch[kNX], ny = s.ch[kNY], nz = s.ch[kNZ];
  for (int x = x0; x < x1; ++x) {
    const std::size_t i = row + x;
    l += ch[kL][i];
    a += ch[kA][i];
    b += ch[kB][i];
    px += ch[kX][i];
    py += ch[kY][i];
    pz += ch[kZ][i];
    nx += ch[kNX][i];
    ny += ch[kNY][i];
    nz += ch[kNZ][i];
  }
  static_assert(kNumChannels == 9 && kL == 0 && kNZ == 8, "channel order of s.ch below");
  s.ch = {l, a, b, px, py, pz, nx, ny, nz};
}

#if defined(FINDMUG_AVX2_DISPATCH)
// addRunChannels four pixels at a time: channels 0-3 and 4-7 of four pixels
// are loaded as rows and transposed, so that one pixel's (L, a, b, x) and
// (y, z, nx, ny) each convert to doubles and add in one instruction; nz goes
// one by one. Each sum still adds the run's pixels one after the other in
// image order (a lane per sum), so the centres are the same bits. Why: the
// scalar loop converts and adds nine floats per pixel one at a time, and
// that, not the additions' latency, bounds it.
__attribute__((target("avx2"))) inline void addRunChannelsAvx2(const float* const* ch,
                                                               std::size_t row, int x0, int x1,
                                                               CentreSum& s) {
  static_assert(kL == 0 && kA == 1 && kB == 2 && kX == 3 && kY == 4 && kZ == 5 && kNX == 6 &&
                    kNY == 7 && kNZ == 8,
                "lanes of first and second below");
  __m256d first = _mm256_loadu_pd(s.ch.data());       // L a b x
  __m256d second = _mm256_loadu_pd(s.ch.data() + 4);  // y z nx ny
  double nz = s.ch[kNZ];
  int x = x0;
  for (; x + 4 <= x1; x += 4) {
    const std::size_t i = row + x;
    __m128 p0 = _mm_loadu_ps(ch[0] + i), p1 = _mm_loadu_ps(ch[1] + i);
    __m128 p2 = _mm_loadu_ps(ch[2] + i), p3 = _mm_loadu_ps(ch[3] + i);
    __m128 q0 = _mm_loadu_ps(ch[4] + i), q1 = _mm_loadu_ps(ch[5] + i);
    __m128 q2 = _mm_loadu_ps(ch[6] + i), q3 = _mm_loadu_ps(ch[7] + i);
    _MM_TRANSPOSE4_PS(p0, p1, p2, p3);  // p0 = channels 0-3 of pixel i, p1 of i + 1, ...
    _MM_TRANSPOSE4_PS(q0, q1, q2, q3);
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p0));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q0));
    nz += ch[kNZ][i];
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p1));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q1));
    nz += ch[kNZ][i + 1];
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p2));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q2));
    nz += ch[kNZ][i + 2];
    first = _mm256_add_pd(first, _mm256_cvtps_pd(p3));
    second = _mm256_add_pd(second, _mm256_cvtps_pd(q3));
    nz += ch[kNZ][i + 3];
  }
  _mm256_storeu_pd(s.ch.data(), first);
  _mm256_storeu_pd(s.ch.data() + 4, second);
  s.ch[kNZ] = nz;
  addRunChannels(ch, row, x, x1, s);  // the last pixels
}
#endif

// `avx2`: assignWindowAvx when the CPU has AVX2, the SSE2 loop otherwise
// (the tests compare the two: OversegSimd::Off).
inline void assignWindow(const FeatureGrid& g, const std::array<float, kNumChannels>& c,
                         const Weights& wt, int label, int x0, int x1, int y0, int y1, float* best,
                         int* labels, bool avx2) {
#if defined(FINDMUG_AVX2_DISPATCH)
  if (avx2) {
    assignWindowAvx(g, c, wt, label, x0, x1, y0, y1, best, labels);
    return;
  }
#else
  (void)avx2;
#endif
  assignWindowSse(g, c, wt, label, x0, x1, y0, y1, best, labels);
}

#if defined(FINDMUG_AVX2_DISPATCH)
// refineToFullResolution's first test for full pixels x0..x0+7 of a row
// (x0 even, 2 <= x0, x0 + 8 <= width, x0 / 2 + 7 <= coarse width): `points`
// is the row's first point, row_a and row_b the two coarse label rows. Pixel
// x's samples are coarse columns x / 2 and x / 2 - 1 (x even) or x / 2 + 1
// (x odd), in both rows. Writes out[x0..x0+7] for the lanes that are not
// usable (-1) or whose four samples agree (their label, or kUnassigned), as
// the scalar code does, and returns the mask of the other lanes (usable,
// samples differ), which the scalar code then decides one by one.
__attribute__((target("avx2"))) inline int refineBlockAvx2(const Eigen::Vector3f* points,
                                                           const int* row_a, const int* row_b,
                                                           int x0, int* out) {
  const int c = x0 / 2;
  // Coarse columns c-1 .. c+6; the lanes use c-1 .. c+4.
  const __m256i a = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row_a + c - 1));
  const __m256i b = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(row_b + c - 1));
  const __m256i own = _mm256_setr_epi32(1, 1, 2, 2, 3, 3, 4, 4);    // x / 2
  const __m256i other = _mm256_setr_epi32(0, 2, 1, 3, 2, 4, 3, 5);  // x / 2 -+ 1
  const __m256i a0 = _mm256_permutevar8x32_epi32(a, own);
  const __m256i agree = _mm256_and_si256(
      _mm256_and_si256(_mm256_cmpeq_epi32(a0, _mm256_permutevar8x32_epi32(a, other)),
                       _mm256_cmpeq_epi32(a0, _mm256_permutevar8x32_epi32(b, own))),
      _mm256_cmpeq_epi32(a0, _mm256_permutevar8x32_epi32(b, other)));
  // usable(): z > 0 and every coordinate finite (|v| < inf, false for NaN).
  __m256 x, y, z;
  detail::loadVec3x8(points[x0].data(), x, y, z);
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  const __m256 finite_x = _mm256_cmp_ps(_mm256_and_ps(x, abs_mask), inf, _CMP_LT_OQ);
  const __m256 finite_y = _mm256_cmp_ps(_mm256_and_ps(y, abs_mask), inf, _CMP_LT_OQ);
  const __m256 finite_z = _mm256_cmp_ps(_mm256_and_ps(z, abs_mask), inf, _CMP_LT_OQ);
  const __m256i usable = _mm256_castps_si256(
      _mm256_and_ps(_mm256_and_ps(_mm256_cmp_ps(z, _mm256_setzero_ps(), _CMP_GT_OQ), finite_x),
                    _mm256_and_ps(finite_y, finite_z)));
  const __m256i label = _mm256_blendv_epi8(_mm256_set1_epi32(kUnassigned), a0,
                                           _mm256_cmpgt_epi32(a0, _mm256_set1_epi32(-1)));
  const __m256i decided = _mm256_and_si256(usable, agree);
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + x0),
                      _mm256_blendv_epi8(_mm256_set1_epi32(-1), label, decided));
  return _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_andnot_si256(agree, usable)));
}
#endif

}  // namespace findmug::detail::organized
