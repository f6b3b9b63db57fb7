// findmug/features/scene_features.hpp — where a patch sits in the frame's 3-D layout.
//
// The 14 paper features describe a patch alone, the region features the
// surface it is part of. With about 25 training frames the forest confuses
// classes that look alike patch by patch but differ in what surrounds them:
// a cabinet front and a wall (both vertical, both textured), a table top and
// a chair seat (both horizontal at knee-to-hip height). Four features of the
// patch's surroundings, in the ground frame:
//   scene_top_gap        how far the frame's top (the 98th percentile of point
//                        heights) lies above the patch's highest point (m): walls
//                        reach it, furniture stays below it
//   column_depth_ratio   the patch's horizontal distance from the camera over
//                        the largest such distance among the points of its
//                        image column band (features.scene_band_px pixels
//                        wide): 1 at the back of the room (walls), < 1 for
//                        things standing in front of something visible above
//                        or below them (cabinets, tables, chairs)
//   fill_below           share of the height bins between the floor and the
//                        patch's lowest point that hold points in the 3x3
//                        ground cells around its centroid (cells and bins
//                        features.scene_cell_m): a cabinet top has its body
//                        below it, a table top mostly free space
//   fill_above           the same above the patch's highest point, up to the
//                        frame's top: a wall continues upwards, a table top
//                        holds a few objects, a chair seat has its back
// Cost: one pass over the valid points (a height histogram, a bitmask per
// ground cell, the farthest point per column band) and one over each patch's
// 3x3 cells.
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "findmug/cloud/cloud.hpp"
#include "findmug/features/features.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"

namespace findmug {

struct SceneConfig {
  bool enabled = false;      // features.scene
  float cell_m = 0.1f;       // features.scene_cell_m: ground cell side and height bin (m)
  int band_px = 20;          // features.scene_band_px: image column band width (pixels)
};

inline constexpr int kSceneFeatureDim = 4;
inline constexpr std::array<std::string_view, kSceneFeatureDim> kSceneFeatureNames = {
    "scene_top_gap", "column_depth_ratio", "fill_below", "fill_above"};

// `cloud_ground` shares the oversegmentation's grid; `features` are the
// segments' base features (centroid, min and max height) and
// `camera_position` is the camera's origin in the ground frame. Returns
// kSceneFeatureDim values per segment, row-major. Throws findmug::Error when
// the grids or the segment counts disagree, or a setting is out of range.
std::vector<float> computeSceneFeatures(const OrganizedCloud& cloud_ground,
                                        const Oversegmentation& segmentation,
                                        const SegmentFeatures& features,
                                        const Eigen::Vector3f& camera_position,
                                        const SceneConfig& config);
// The same into `out`, reusing the memory it holds. `out` must not be
// features.scene.
void computeSceneFeaturesInto(const OrganizedCloud& cloud_ground,
                              const Oversegmentation& segmentation,
                              const SegmentFeatures& features,
                              const Eigen::Vector3f& camera_position, const SceneConfig& config,
                              std::vector<float>& out);

}  // namespace findmug
