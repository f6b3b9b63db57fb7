// findmug/labels/label_holes.hpp — labels for the pixels the depth camera left without depth.
//
// A pixel without depth has no point, so no patch and no label: on a live
// Kinect's raw depth that is 5-15 % of the image (the projector's shadow
// beside near objects, ragged depth edges, dark or shiny surfaces), and a
// label image full of holes is what a user watching the robot sees and what
// the accuracy over all labelled pixels counts as wrong. fillLabelHoles()
// gives each unlabelled pixel the label of the labelled pixels around it:
//   1. along its row: a run of unlabelled pixels between two labelled ones
//      takes their label when they agree; when they differ, the label of
//      the side that is farther from the camera. The Kinect's projector sits
//      beside its camera, so its shadows are runs along the rows lying on
//      the surface behind the near object (the far side), and a depth edge's
//      ragged band belongs to either side about equally;
//   2. along its column, for what the rows left (runs at the left or right
//      border, vertical gaps), by the same rule;
//   3. a run with a labelled pixel on one side only (the image border) takes
//      that side's label.
// Runs longer than `max_run_px` stay unlabelled: a window, a mirror or
// everything beyond the camera's range is not guessed from its border.
// Filled pixels get confidence 0 (a label without evidence of its own); the
// 3-D stages never see them, as they have no point.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "findmug/labels/label_image.hpp"

namespace findmug {

struct LabelHoleFillConfig {
  bool enabled = true;  // labels.fill_holes
  int max_run_px = 64;  // labels.fill_max_run_px (1..10000)
};

// Fills the void pixels of `labels` in place as above; `depth_mm` (the
// frame's depth on the same grid, 0 = none) says which side is farther.
// Returns how many pixels it filled. Throws findmug::Error when the sizes
// disagree. Does nothing when `config.enabled` is false.
std::size_t fillLabelHoles(const std::vector<std::uint16_t>& depth_mm,
                           const LabelHoleFillConfig& config, LabelImage& labels);

}  // namespace findmug
