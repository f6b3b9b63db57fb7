// point_extent.hpp — internal to findmug_core: the extent of a cloud's
// points with a finite z, for the cell grid of the scene features.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace findmug::detail {

struct PointExtent {
  float min_x, min_y, max_x, max_y, max_z;
};

// Minimum and maximum x and y, and maximum z, over the points whose z is
// finite; infinite (min +inf, max -inf) when there is none. The extremes are
// running minima and maxima with std::min / std::max's rule (a NaN x or y
// never replaces an extreme). Out of line and with x and y in one SSE
// register: in the caller's loop the compiler kept three of the extremes in
// memory, so every point waited for the previous point's stores.
// _mm_min_ps(p, lo) is p < lo ? p : lo, which is std::min(lo, p); max alike.
__attribute__((noinline)) inline PointExtent pointExtent(
    const std::vector<Eigen::Vector3f>& points) {
  const float inf = std::numeric_limits<float>::infinity();
#if defined(__SSE2__)
  __m128 min_xy = _mm_set1_ps(inf), max_xy = _mm_set1_ps(-inf), max_z = _mm_set_ss(-inf);
  for (const auto& p : points) {
    if (!std::isfinite(p.z())) continue;
    // x and y into the low lanes (an 8-byte load; __m64 may alias floats).
    const __m128 xy = _mm_loadl_pi(_mm_setzero_ps(), reinterpret_cast<const __m64*>(p.data()));
    min_xy = _mm_min_ps(xy, min_xy);
    max_xy = _mm_max_ps(xy, max_xy);
    max_z = _mm_max_ss(_mm_set_ss(p.z()), max_z);
  }
  alignas(16) float lo[4], hi[4];
  _mm_store_ps(lo, min_xy);
  _mm_store_ps(hi, max_xy);
  return {lo[0], lo[1], hi[0], hi[1], _mm_cvtss_f32(max_z)};
#else
  PointExtent e{inf, inf, -inf, -inf, -inf};
  for (const auto& p : points) {
    if (!std::isfinite(p.z())) continue;
    e.min_x = std::min(e.min_x, p.x());
    e.max_x = std::max(e.max_x, p.x());
    e.min_y = std::min(e.min_y, p.y());
    e.max_y = std::max(e.max_y, p.y());
    e.max_z = std::max(e.max_z, p.z());
  }
  return e;
#endif
}

}  // namespace findmug::detail
