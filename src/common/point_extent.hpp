// point_extent.hpp — internal to findmug_core: the extent of a cloud's
// points with a finite z, for the cell grid of the scene features.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/min_max2.hpp"

namespace findmug::detail {

struct PointExtent {
  float min_x, min_y, max_x, max_y, max_z;
};

// Minimum and maximum x and y, and maximum z, over the points whose z is
// finite; infinite (min +inf, max -inf) when there is none. The extremes are
// running minima and maxima with std::min / std::max's rule (a NaN x or y
// never replaces an extreme). Out of line, with x and y in a MinMax2: in the
// caller's loop the compiler kept three of the extremes in memory, so every
// point waited for the previous point's stores.
__attribute__((noinline)) inline PointExtent pointExtent(
    const std::vector<Eigen::Vector3f>& points) {
  const float inf = std::numeric_limits<float>::infinity();
  MinMax2 xy(inf, -inf);
  float max_z = -inf;
  for (const auto& p : points) {
    if (!std::isfinite(p.z())) continue;
    xy.add(p.data());
    max_z = std::max(max_z, p.z());
  }
  float lo[2], hi[2];
  xy.get(lo, hi);
  return {lo[0], lo[1], hi[0], hi[1], max_z};
}

}  // namespace findmug::detail
