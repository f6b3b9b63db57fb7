// moments_internal.hpp (internal) — pooling segments' moments into those of their union.
//
// Shared by the region features and the object features, which both merge
// whole segments without another pass over their pixels.
#pragma once

#include <algorithm>

#include "findmug/features/features.hpp"

namespace findmug::detail {

// Pools b into a (Chan et al.'s pairwise update): the mean and the scatter
// about the mean of the union, with no raw second moments, so no
// cancellation however far the points are from the origin.
inline void poolMoments(SegmentMoments& a, const SegmentMoments& b) {
  if (b.count == 0) return;
  if (a.count == 0) {
    a = b;
    return;
  }
  const double n = a.count + b.count;
  const Eigen::Vector3d delta = b.mean - a.mean;
  a.scatter += b.scatter + (a.count * b.count / n) * (delta * delta.transpose());
  a.mean += delta * (b.count / n);
  a.count = n;
  a.normal_sum += b.normal_sum;
  a.max_z = std::max(a.max_z, b.max_z);
}

}  // namespace findmug::detail
