// table_objects_internal.hpp — what the table-top objects' source files share (internal to
// src/objects): the sampled clustering of step 2 and its working memory, and the colour
// bins of an object's histogram.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <vector>

#include "findmug/objects/table_objects.hpp"

namespace findmug::objects_detail {

// clusterSampled's working memory, kept per thread between frames: the sampled points,
// their pixels and clusters, and per image pixel the sampled point there (-1 elsewhere;
// only the entries set are reset after use).
struct SampledClusteringScratch {
  std::vector<Eigen::Vector3f> sample_points;
  // sample_of: union-find parents, then each sampled point's cluster.
  std::vector<int> sample_pixels, sample_of, sample_cluster_of_root, sample_at_pixel;
  std::vector<int> sample_index;  // per point of the clustered set: its sampled index or -1
};

// Step 2 with table_objects.point_stride = s > 1: the points at pixels (x, y)
// with x and y multiples of s are clustered on the image grid (a cluttered
// NYU desk holds up to 54,000 points above its top; the exact clustering's
// voxel pass was most of the stage's cost there, and sampling alone does not
// cut the number of voxels): two sampled points are linked when they are
// within kOrganizedReachSteps sampled steps of each other in the image and
// within cluster_tolerance_m in 3-D, and the clusters are the linked sets.
// Every other point then joins the cluster of the nearest of the four sampled
// pixels around it that lies within cluster_tolerance_m (else of the twelve
// around those). A point with none (a
// depth edge, a thin strand) joins no cluster: it is given the id returned
// (the cluster count), which the caller never makes a candidate. Unlike the
// exact clustering, parts close in 3-D but further apart in the image stay
// apart. With s = 1: the exact clustering; no point is left out. Returns the
// number of clusters, numbered in pixel order of their first sampled point.
int clusterSampled(const std::vector<Eigen::Vector3f>& points, const std::vector<int>& pixels,
                   float tolerance, int width, int height, int stride, SampledClusteringScratch& s,
                   std::vector<int>& cluster_of);

// HSV bin of one colour (see ObjectColourHistogram).
inline int colourBin(const Rgb8& c) {
  const int r = c.r, g = c.g, b = c.b;
  const int hi = std::max({r, g, b}), lo = std::min({r, g, b});
  const float value = static_cast<float>(hi) / 255.0f;
  const float saturation = hi > 0 ? static_cast<float>(hi - lo) / static_cast<float>(hi) : 0.0f;
  if (saturation >= 0.2f && value >= 0.15f) {
    const float d = static_cast<float>(hi - lo);
    float hue;  // degrees, [0, 360)
    if (hi == r) {
      hue = 60.0f * static_cast<float>(g - b) / d;
      if (hue < 0) hue += 360.0f;
    } else if (hi == g) {
      hue = 60.0f * (static_cast<float>(b - r) / d + 2.0f);
    } else {
      hue = 60.0f * (static_cast<float>(r - g) / d + 4.0f);
    }
    const int sector = std::min(11, static_cast<int>(hue / 30.0f));
    return sector * 2 + (saturation >= 0.5f ? 1 : 0);
  }
  return 24 + std::min(3, static_cast<int>(value * 4.0f));
}

// counts / total per bin (all 0 when total is 0).
inline void normaliseColourCounts(const std::array<int, kObjectColourBins>& counts, int total,
                                  ObjectColourHistogram& out) {
  out.fill(0.0f);
  if (total <= 0) return;
  for (int k = 0; k < kObjectColourBins; ++k) {
    out[static_cast<std::size_t>(k)] =
        static_cast<float>(counts[static_cast<std::size_t>(k)]) / static_cast<float>(total);
  }
}

}  // namespace findmug::objects_detail
