// min_max2.hpp — internal to findmug_core: the running minimum and maximum
// of (x, y) pairs, for the per-point passes that need a 2-D extent (the scene
// grid, the table top's boxes).
#pragma once

#include <algorithm>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace findmug::detail {

// Both extremes in one SSE register each. Written as running values in a
// larger loop, the compiler kept such extremes on the stack, and every point
// waited for the previous point's stores. Each step keeps std::min's and
// std::max's rule (and so Eigen's AlignedBox::extend): minps(p, lo) is
// p < lo ? p : lo, which is std::min(lo, p); a NaN never replaces an extreme.
class MinMax2 {
 public:
  // The extremes before any pair: e.g. +inf / -inf, or an empty Eigen box's
  // highest / lowest.
  MinMax2(float lo_start, float hi_start)
#if defined(__SSE2__)
      : lo_(_mm_set1_ps(lo_start)), hi_(_mm_set1_ps(hi_start)) {
  }
#else
      : lo_{lo_start, lo_start}, hi_{hi_start, hi_start} {
  }
#endif

  // A pair in registers. Use this, not add(const float*), for values the
  // caller has just stored one float at a time: an 8-byte load of two 4-byte
  // stores cannot be forwarded from the store buffer, and waits for both.
  void add(float x, float y) {
#if defined(__SSE2__)
    extend(_mm_unpacklo_ps(_mm_set_ss(x), _mm_set_ss(y)));
#else
    extendScalar(x, y);
#endif
  }
  // The pair at xy[0], xy[1] (one 8-byte load).
  void add(const float* xy) {
#if defined(__SSE2__)
    // __m64 may alias floats.
    extend(_mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(xy)));
#else
    extendScalar(xy[0], xy[1]);
#endif
  }

  // lo[0..1] = minimum x, y; hi[0..1] = maximum x, y.
  void get(float lo[2], float hi[2]) const {
#if defined(__SSE2__)
    alignas(16) float l[4], h[4];
    _mm_store_ps(l, lo_);
    _mm_store_ps(h, hi_);
    lo[0] = l[0], lo[1] = l[1], hi[0] = h[0], hi[1] = h[1];
#else
    lo[0] = lo_[0], lo[1] = lo_[1], hi[0] = hi_[0], hi[1] = hi_[1];
#endif
  }

 private:
#if defined(__SSE2__)
  void extend(__m128 xy) {
    lo_ = _mm_min_ps(xy, lo_);
    hi_ = _mm_max_ps(xy, hi_);
  }
  __m128 lo_, hi_;
#else
  void extendScalar(float x, float y) {
    lo_[0] = std::min(lo_[0], x), lo_[1] = std::min(lo_[1], y);
    hi_[0] = std::max(hi_[0], x), hi_[1] = std::max(hi_[1], y);
  }
  float lo_[2], hi_[2];
#endif
};

}  // namespace findmug::detail
