// findmug/labels/label_image.hpp — per-pixel labels and confidence.
#pragma once

#include <cstdint>
#include <vector>

#include "findmug/labels/labels.hpp"
#include "findmug/oversegmentation/oversegmentation.hpp"

namespace findmug {

struct LabelImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> labels;  // kVoidLabel where depth is invalid / no segment
  std::vector<float> confidence;     // 0 where void
};

// Paints every segment's label and confidence onto its pixels.
LabelImage projectLabels(const Oversegmentation& segmentation,
                         const std::vector<std::uint8_t>& segment_labels,
                         const std::vector<float>& segment_confidence);
// The same into `out`, reusing the memory it holds.
void projectLabelsInto(const Oversegmentation& segmentation,
                       const std::vector<std::uint8_t>& segment_labels,
                       const std::vector<float>& segment_confidence, LabelImage& out);

// Colour overlay in the paper's palette, blended with `rgb` (alpha = label weight).
std::vector<Rgb8> colorizeLabels(const LabelImage& labels, const std::vector<Rgb8>& rgb,
                                 float alpha = 0.6f);

}  // namespace findmug
