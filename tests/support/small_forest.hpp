// Test support: a small forest trained on one labelled frame.
//
// Unit tests of the segmenter and its buffers need a model that knows the
// frame they run on; this trains one (4 trees, depth 6) on the frame's
// patches with their majority true labels, through the segmenter's own stages.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "findmug/frame/frame.hpp"
#include "findmug/learner/forest.hpp"
#include "findmug/offline/training.hpp"
#include "findmug/segmenter/segmenter.hpp"

namespace findmug::test {

inline std::shared_ptr<const RandomForest> trainSmallForest(const Segmenter& segmenter,
                                                            const RgbdFrame& frame,
                                                            const std::vector<std::uint8_t>& truth) {
  SegmentedFrame segmented = segmenter.oversegment(segmenter.prepare(frame));
  const SegmentFeatures features = segmenter.features(segmented);
  const auto labels = segmentMajorityLabels(segmented.segmentation, truth);
  TrainingSet set;
  for (std::size_t k = 0; k < labels.size(); ++k) {
    if (labels[k] >= kNumLabels) continue;
    set.features.push_back(features.features[k]);
    set.labels.push_back(labels[k]);
  }
  ForestParams params;
  params.num_trees = 4;
  params.max_depth = 6;
  return std::make_shared<const RandomForest>(RandomForest::train(set, params));
}

}  // namespace findmug::test
