// findmug/offline/object_stage.hpp — a forest over whole object candidates, fused into the
// patch posterior (issue 35, item 3's optional lever; evaluation only).
//
// A patch sees a piece of a thing; the object candidates of object_features.hpp see the
// thing: how tall, how large its top, whether a back rises behind it. The patch forest
// already reads three of those columns; this stage instead classifies each object
// candidate as a whole, with one training example per object (its label the pixel
// plurality of its labelled patches), and mixes the object's distribution into the
// posterior of each of its patches before the MRF:
//     p'(y) = (1 - w) p_patch(y) + w p_object(y)
// Only object candidates take part: floor, wall and ceiling planes keep the patch
// posterior. The row of an object is the pixel-weighted mean of its patches' 14 base
// features followed by its own columns (kObjectStageColumns).
#pragma once

#include <array>
#include <string_view>
#include <vector>

#include "findmug/learner/forest.hpp"
#include "findmug/offline/training.hpp"

namespace findmug {

struct ObjectStageConfig {
  float weight = 0.0f;  // w above; 0 = off
  ForestParams forest;  // the object forest (its own, smaller leaves)
};

inline constexpr int kObjectStageColumns = 11;
inline constexpr std::array<std::string_view, kObjectStageColumns> kObjectStageNames = {
    "object_height_span", "object_min_height", "object_max_height", "object_footprint_area",
    "object_extent_major", "object_extent_minor", "object_top_height", "object_top_area",
    "object_back_rise", "object_wall_distance", "object_segment_count"};

// One frame's object candidates as rows.
struct ObjectRows {
  std::vector<int> segment_row;       // segment -> row, -1 for planes
  std::vector<FeatureVector> base;    // per row
  std::vector<float> extra;           // per row, kObjectStageColumns
  std::vector<std::uint8_t> labels;   // per row, plurality label (kVoidLabel without one)
  std::vector<float> pixels;          // per row, pixel count
};

// The object candidates of `sample` (grouped with `config.objects`' thresholds, whether
// features.objects is on or not).
ObjectRows objectRowsOf(const FrameSample& sample, const SegmenterConfig& config);

// A forest trained on the labelled object candidates of `frames`.
RandomForest trainObjectForest(const std::vector<const FrameSample*>& frames,
                               const SegmenterConfig& config, const ForestParams& params);

// Mixes the object forest's answer into each object patch's distribution (see above).
void fuseObjectPosterior(const RandomForest& object_forest, const FrameSample& sample,
                         const SegmenterConfig& config, float weight,
                         std::vector<ClassProbabilities>& probabilities);

}  // namespace findmug
