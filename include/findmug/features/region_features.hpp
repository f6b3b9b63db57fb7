// findmug/features/region_features.hpp — features of the larger surface a patch belongs to.
//
// Oversegmentation patches are small (about 0.1 m); whether a horizontal patch
// at 0.7 m is a table or a chair seat shows better in the surface it is part
// of. Neighbouring patches (over the oversegmentation's adjacency graph) are
// merged into regions when their mean normals agree within
// `features.region_normal_angle_deg` and each centroid lies within
// `features.region_plane_distance_m` of the other patch's plane (a
// smoothness criterion: a curved or bent surface grows as long as each step
// is smooth). Every patch then gets the features of its region, computed
// in the ground frame from the points of all its patches:
//   region_area            major x minor extent (m²)
//   region_extent_major    sqrt(12 λ) of the largest scatter eigenvalue (m): the
//   region_extent_minor    side of a uniform rectangle with that variance; same
//                          for the middle eigenvalue
//   region_centroid_height centroid height above ground (m)
//   region_max_height      highest point (m)
//   region_normal_angle    angle between the region's mean normal and +z (rad)
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "findmug/cloud/cloud.hpp"
#include "findmug/features/features.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"

namespace findmug {

struct RegionConfig {
  bool enabled = false;            // features.regions
  float normal_angle_deg = 10.0f;  // features.region_normal_angle_deg
  float plane_distance_m = 0.03f;  // features.region_plane_distance_m
};

inline constexpr int kRegionFeatureDim = 6;
inline constexpr std::array<std::string_view, kRegionFeatureDim> kRegionFeatureNames = {
    "region_area",       "region_extent_major", "region_extent_minor", "region_centroid_height",
    "region_max_height", "region_normal_angle"};

struct RegionFeatures {
  std::vector<int> segment_region;  // segment -> region index (0..region_count-1)
  int region_count = 0;
  std::vector<float> values;  // row-major, kRegionFeatureDim per segment
};

// From the points: `cloud_ground` and `normals_ground` share the
// oversegmentation's grid. Throws findmug::Error when the grids disagree or a
// segment has no valid point.
RegionFeatures computeRegionFeatures(const OrganizedCloud& cloud_ground,
                                     const NormalImage& normals_ground,
                                     const Oversegmentation& segmentation,
                                     const RegionConfig& config);
// The same into `out`, reusing the memory it holds.
void computeRegionFeaturesInto(const OrganizedCloud& cloud_ground,
                               const NormalImage& normals_ground,
                               const Oversegmentation& segmentation, const RegionConfig& config,
                               RegionFeatures& out);

// From the segments' moments (computeFeatures of the same segmentation), with
// no pass over the pixels: the same regions and, up to rounding in the last
// bits, the same values as from the points (the segment sums are pooled
// instead of summed point by point). The Segmenter uses this one: the pixel
// pass cost as much as the 14-D features themselves. Throws findmug::Error
// when `features` does not match the segmentation.
RegionFeatures computeRegionFeatures(const SegmentFeatures& features,
                                     const Oversegmentation& segmentation,
                                     const RegionConfig& config);
void computeRegionFeaturesInto(const SegmentFeatures& features,
                               const Oversegmentation& segmentation, const RegionConfig& config,
                               RegionFeatures& out);

}  // namespace findmug
